#include "flatsos/planner/joint_paths.hpp"

#include <stdexcept>

namespace flatsos::planner {

Jet JointPath::jet(double t, int orders) const {
  Jet out(static_cast<Eigen::Index>(q.size()), orders);
  for (std::size_t i = 0; i < q.size(); ++i)
    for (int k = 0; k < orders; ++k) out(static_cast<Eigen::Index>(i), k) = q[i].derivativeAt(t, k);
  return out;
}

JointPath fit_joint_path(double T, const Eigen::MatrixXd& initial, const Eigen::MatrixXd& terminal) {
  if (initial.rows() != terminal.rows())
    throw std::invalid_argument("joint path: initial and terminal conditions have " + std::to_string(initial.rows()) +
                                " and " + std::to_string(terminal.rows()) + " joints");
  JointPath path;
  path.duration_s = T;
  for (Eigen::Index i = 0; i < initial.rows(); ++i)
    path.q.push_back(hermite_interpolant(T, initial.row(i).transpose(), terminal.row(i).transpose()));
  return path;
}

}  // namespace flatsos::planner
