#include "flatsos/planner/joint_paths.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace flatsos::planner {

Jet JointPath::jet(double t, int orders) const {
  Jet out(numJoints(), orders);
  jetInto(t, out);
  return out;
}

JointPath JointPath::fromSpline(SplineTrajectory s) {
  JointPath path;
  path.duration_s = s.duration();
  path.spline = std::move(s);
  return path;
}

void JointPath::jetInto(double t, Eigen::Ref<Jet> out) const {
  if (out.rows() != numJoints())
    throw std::invalid_argument("joint path jet: the output has " + std::to_string(out.rows()) + " rows, the path " +
                                std::to_string(numJoints()) + " joints");
  if (spline) {
    // Beyond [0, T] as the polynomial path: continued (the torque jets' differences reach past
    // the ends; a frozen path there made tau' and tau'' at t = 0 and T wrong).
    spline->continuedJetInto(t, out);
    return;
  }
  for (std::size_t i = 0; i < q.size(); ++i)
    for (Eigen::Index k = 0; k < out.cols(); ++k)
      out(static_cast<Eigen::Index>(i), k) = q[i].derivativeAt(t, static_cast<int>(k));
}

std::vector<TorqueJet> torque_jets_on_grid(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                           const JointPath& path, double h, int count) {
  if (!path.spline) return flat.torqueJetsOnGrid(workspace, [&](double t) { return path.jet(t, 4); }, 0.0, h, count);
  if (count < 1 || !(h > 0.0)) throw std::invalid_argument("torque jets on a grid: need count >= 1 and h > 0");
  std::vector<TorqueJet> jets;
  jets.reserve(static_cast<std::size_t>(count));
  Jet q_jet(path.numJoints(), 5);
  for (int i = 0; i < count; ++i) {
    path.jetInto(h * i, q_jet);
    jets.push_back(flat.torqueJet(workspace, q_jet));
  }
  return jets;
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

void fit_rest_cubic(double T, const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& q_target,
                    JointPath& out) {
  if (!(T > 0.0) || !std::isfinite(T)) throw std::invalid_argument("joint path: horizon T must be > 0 s");
  if (qd.size() != q.size() || q_target.size() != q.size())
    throw std::invalid_argument("joint path: q, qd and the target need one entry per joint");
  if (!q.allFinite() || !qd.allFinite() || !q_target.allFinite())
    throw std::invalid_argument("joint path: boundary derivatives must be finite");
  out.duration_s = T;
  out.q.resize(static_cast<std::size_t>(q.size()));
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    // q(t) = q0 + v0 t + c2 t^2 + c3 t^3 with q(T) = target, qd(T) = 0.
    const double dq = q_target[i] - q[i], v0 = qd[i];
    const Eigen::Vector4d c(q[i], v0, (3.0 * dq - 2.0 * v0 * T) / (T * T), (v0 * T - 2.0 * dq) / (T * T * T));
    out.q[static_cast<std::size_t>(i)].setCoefficients(c);
  }
}

}  // namespace flatsos::planner
