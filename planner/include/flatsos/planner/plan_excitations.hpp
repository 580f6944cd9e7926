#pragma once
// The excitations a receding-horizon plan asks for (constant flat outputs Y = alpha along a
// joint path, held at rest after its end): the inverse map at uniform times, with the torque
// offset the plan was made for. The controller applies exactly these; a single planning step
// returns them too (RecedingHorizonStep::excitations).

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <Eigen/Core>

#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/joint_paths.hpp"

namespace flatsos::planner {

/// Reusable storage for sample_plan_excitations (allocation-free once used for one size).
struct PlanExcitationScratch {
  TorqueJetGrid torque_grid;
  Jet joint_jet, flat_jet;  ///< N x 5, p x 3
  MusclePoint point;
};

/// q, qd, ... of the path at tau into out (N x out.cols()); after the path's end, its final
/// posture at rest.
void rest_held_jet(const JointPath& path, double tau_s, Jet& out);

/// Excitations at `count` times tau0 + i h (s from the plan's start) into `out` (count x m).
/// `torque_offset_N_m`: empty or one per joint (the torque the muscles need not produce).
/// `activations` (optional): the activations at the same times, count x m. Returns false, leaving
/// the outputs partly written, when an excitation is not finite (the plan left the model's
/// valid domain there).
bool sample_plan_excitations(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const JointPath& path,
                             const Eigen::VectorXd& alpha, const Eigen::VectorXd& torque_offset_N_m, double tau0_s,
                             double h_s, int count, PlanExcitationScratch& scratch, Eigen::MatrixXd& out,
                             Eigen::MatrixXd* activations = nullptr);

}  // namespace flatsos::planner
