#include "flatsos/planner/plan_excitations.hpp"

#include <algorithm>

namespace flatsos::planner {

void rest_held_jet(const JointPath& path, double tau, Jet& out) {
  path.jetInto(std::min(tau, path.duration_s), out);
  if (tau >= path.duration_s && out.cols() > 1) out.rightCols(out.cols() - 1).setZero();
}

bool sample_plan_excitations(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const JointPath& path,
                             const Eigen::VectorXd& alpha, const Eigen::VectorXd& torque_offset_N_m, double tau0,
                             double h, int count, PlanExcitationScratch& s, Eigen::MatrixXd& out,
                             Eigen::MatrixXd* activations) {
  s.joint_jet.resize(flat.numJoints(), 5);
  s.flat_jet.setZero(flat.numFlatOutputs(), 3);
  out.resize(count, flat.numMuscles());
  if (activations) activations->resize(count, flat.numMuscles());
  flat.torqueJetsOnGrid(
      workspace, [&](double tau, Jet& jet) { rest_held_jet(path, tau, jet); }, tau0, h, count, s.torque_grid);
  s.flat_jet.col(0) = alpha;  // constant Y: its rates stay zero
  for (int i = 0; i < count; ++i) {
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
