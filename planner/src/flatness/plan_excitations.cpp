#include "flatsos/planner/plan_excitations.hpp"

#include <algorithm>

namespace flatsos::planner {

void rest_held_jet(const JointPath& path, double tau, Jet& out) {
  path.jetInto(std::min(tau, path.duration_s), out);
  if (tau >= path.duration_s && out.cols() > 1) out.rightCols(out.cols() - 1).setZero();
}

void FlatOutputStart::blend(double t, int which, double out[3]) const {
  out[0] = out[1] = out[2] = 0.0;
  if (empty() || !(blend_s > 0.0) || t >= blend_s) return;
  const double T = blend_s, s = std::max(t, 0.0) / T;
  if (which == 0) {  // (1 - s)^3 (1 + 3 s)
    out[0] = (1.0 - s) * (1.0 - s) * (1.0 - s) * (1.0 + 3.0 * s);
    out[1] = -12.0 * s * (1.0 - s) * (1.0 - s) / T;
    out[2] = -12.0 * (1.0 - s) * (1.0 - 3.0 * s) / (T * T);
  } else {  // T s (1 - s)^3
    out[0] = T * s * (1.0 - s) * (1.0 - s) * (1.0 - s);
    out[1] = (1.0 - s) * (1.0 - s) * (1.0 - 4.0 * s);
    out[2] = -6.0 * (1.0 - s) * (1.0 - 2.0 * s) / T;
  }
}

void FlatOutputStart::jetInto(const Eigen::VectorXd& alpha, double t, Eigen::Ref<Jet> out) const {
  out.setZero();
  out.col(0) = alpha;
  if (empty()) return;
  double b0[3], b1[3];
  blend(t, 0, b0);
  blend(t, 1, b1);
  for (int k = 0; k < 3 && k < out.cols(); ++k) out.col(k) += (value - alpha) * b0[k] + rate * b1[k];
}

bool sample_plan_excitations(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const JointPath& path,
                             const Eigen::VectorXd& alpha, const Eigen::VectorXd& torque_offset_N_m, double tau0,
                             double h, int count, PlanExcitationScratch& s, Eigen::MatrixXd& out,
                             Eigen::MatrixXd* activations, const FlatOutputStart* start) {
  s.joint_jet.resize(flat.numJoints(), 5);
  s.flat_jet.setZero(flat.numFlatOutputs(), 3);
  out.resize(count, flat.numMuscles());
  if (activations) activations->resize(count, flat.numMuscles());
  flat.torqueJetsOnGrid(
      workspace, [&](double tau, Jet& jet) { rest_held_jet(path, tau, jet); }, tau0, h, count, s.torque_grid);
  s.flat_jet.col(0) = alpha;  // constant Y: its rates stay zero
  const bool blended = start && !start->empty();
  for (int i = 0; i < count; ++i) {
    if (blended) start->jetInto(alpha, tau0 + h * i, s.flat_jet);
    TorqueJet& tj = s.torque_grid.jets[static_cast<std::size_t>(i)];
    // The one place a torque offset meets the muscles: the torque the plan was made for.
    if (torque_offset_N_m.size()) tj.tau.col(0) -= torque_offset_N_m;  // constant: rates unchanged
    rest_held_jet(path, tau0 + h * i, s.joint_jet);
    flat.inverseFromTorque(s.joint_jet, tj, s.flat_jet, s.point);
    if (!s.point.excitation.allFinite()) return false;
    out.row(i) = s.point.excitation.transpose();
    if (activations) activations->row(i) = s.point.activation.transpose();
  }
  return true;
}

}  // namespace flatsos::planner
