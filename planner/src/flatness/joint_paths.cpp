#include "flatsos/planner/joint_paths.hpp"

#include "flatsos/planner/joint_reference.hpp"

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
  if (reference) reference->jetInto(reference_start_s + t, out);
  else out.setZero();
  if (reference && t > correction_end_s) return;  // the correction is over: on the reference
  for (std::size_t i = 0; i < q.size(); ++i)
    for (Eigen::Index k = 0; k < out.cols(); ++k)
      out(static_cast<Eigen::Index>(i), k) += q[i].derivativeAt(t, static_cast<int>(k));
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

namespace {
// The correction that removes a joint's offset from the reference: c^(k)(0) = start[k] for the
// given derivatives (value, speed and, when known, acceleration and jerk), and the value and
// first three derivatives 0 at T, so that the path joins the reference there with its torque and
// the torque's rate continuous (the tendon forces' rates, and so the activations, follow them).
// Coefficients in ascending powers: the start's c_k = start[k] / k!, the last four from the
// end's 4 x 4 system.
void correction_polynomial(const double* start, int known, double T, Polynomial& out) {
  constexpr int kEnd = 4;  // end conditions
  const int degree = known + kEnd - 1;
  Eigen::Matrix<double, 8, 1> c = Eigen::Matrix<double, 8, 1>::Zero();
  double factorial = 1.0;
  for (int k = 0; k < known; ++k) factorial *= (k > 0 ? k : 1), c[k] = start[k] / factorial;
  // Row r: the r-th derivative at T of sum_k c_k t^k, split into the known part and the unknowns.
  Eigen::Matrix4d M = Eigen::Matrix4d::Zero();
  Eigen::Vector4d rhs;
  for (int r = 0; r < kEnd; ++r) {
    double known_part = 0.0;
    for (int k = r; k <= degree; ++k) {
      double falling = 1.0;  // k! / (k - r)!
      for (int i = 0; i < r; ++i) falling *= static_cast<double>(k - i);
      const double term = falling * std::pow(T, k - r);
      if (k < known) known_part += term * c[k];
      else M(r, k - known) = term;
    }
    rhs[r] = -known_part;
  }
  c.segment<kEnd>(known) = M.partialPivLu().solve(rhs);
  out.setCoefficients(c.head(degree + 1));
}
}  // namespace

void fit_tracking_path(double T, double correction_s, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                       const Eigen::VectorXd& qdd, const Eigen::VectorXd& qddd,
                       std::shared_ptr<const JointReference> reference, double t_s, JointPath& out) {
  if (!reference) throw std::invalid_argument("tracking path: no reference");
  if (q.size() != reference->numJoints())
    throw std::invalid_argument("tracking path: the reference has " + std::to_string(reference->numJoints()) +
                                " joints, the state " + std::to_string(q.size()));
  if (!std::isfinite(t_s)) throw std::invalid_argument("tracking path: the time is not finite");
  if (!(T > 0.0) || !std::isfinite(T)) throw std::invalid_argument("tracking path: horizon T must be > 0 s");
  if (!(correction_s > 0.0) || !(correction_s <= T))
    throw std::invalid_argument("tracking path: the correction time must be in (0, horizon]");
  if (qd.size() != q.size()) throw std::invalid_argument("tracking path: q and qd need one entry per joint");
  if (!q.allFinite() || !qd.allFinite()) throw std::invalid_argument("tracking path: the state must be finite");
  const bool start_motion = qdd.size() > 0;
  if (start_motion && (qdd.size() != q.size() || qddd.size() != q.size() || !qdd.allFinite() || !qddd.allFinite()))
    throw std::invalid_argument("tracking path: the starting acceleration and jerk need one finite entry per joint");
  out.duration_s = T;
  out.spline.reset();
  out.q.resize(static_cast<std::size_t>(q.size()));
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    const int joint = static_cast<int>(i);
    double start[4] = {q[i] - reference->derivative(joint, t_s, 0), qd[i] - reference->derivative(joint, t_s, 1), 0.0, 0.0};
    if (start_motion) {
      start[2] = qdd[i] - reference->derivative(joint, t_s, 2);
      start[3] = qddd[i] - reference->derivative(joint, t_s, 3);
    }
    correction_polynomial(start, start_motion ? 4 : 2, correction_s, out.q[static_cast<std::size_t>(i)]);
  }
  out.correction_end_s = correction_s;
  out.reference = std::move(reference);
  out.reference_start_s = t_s;
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
  out.reference.reset();
  out.q.resize(static_cast<std::size_t>(q.size()));
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    // q(t) = q0 + v0 t + c2 t^2 + c3 t^3 with q(T) = target, qd(T) = 0.
    const double dq = q_target[i] - q[i], v0 = qd[i];
    const Eigen::Vector4d c(q[i], v0, (3.0 * dq - 2.0 * v0 * T) / (T * T), (v0 * T - 2.0 * dq) / (T * T * T));
    out.q[static_cast<std::size_t>(i)].setCoefficients(c);
  }
}

}  // namespace flatsos::planner
