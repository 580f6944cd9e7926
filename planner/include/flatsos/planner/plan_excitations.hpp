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

/// Where a receding-horizon plan's flat outputs start: Y(t) = alpha + (value - alpha) phi0(t) +
/// rate phi1(t) over [0, blend_s], alpha after, with the quartic blends phi0 = (1 - s)^3 (1 + 3 s)
/// and phi1 = blend_s s (1 - s)^3, s = t / blend_s (value 1 and slope 0, value 0 and slope 1 at
/// the start; value, slope and curvature 0 at the end). A plan that starts from the muscles'
/// present state (their forces and force rates, through Y and Y') instead of its own; its
/// curvature at the start, -12 (value - alpha) / blend_s^2, leaves the first excitation to alpha. Empty value (blend_s = 0): constant Y = alpha, the paper's plan.
struct FlatOutputStart {
  Eigen::VectorXd value, rate;  ///< Y(0) and Y'(0), N and N/s (p each)
  double blend_s = 0.0;
  bool empty() const { return value.size() == 0; }
  /// phi0 (which = 0) or phi1 (which = 1) and their first two derivatives at t: out[0..2].
  void blend(double t, int which, double out[3]) const;
  /// Y, Y', Y'' at t for the given alpha into out (p x 3; allocates nothing).
  void jetInto(const Eigen::VectorXd& alpha, double t, Eigen::Ref<Jet> out) const;
};

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
/// `activations` (optional): the activations at the same times, count x m. `start` (optional):
/// where the flat outputs start (else constant alpha). Returns false, leaving
/// the outputs partly written, when an excitation is not finite (the plan left the model's
/// valid domain there).
bool sample_plan_excitations(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const JointPath& path,
                             const Eigen::VectorXd& alpha, const Eigen::VectorXd& torque_offset_N_m, double tau0_s,
                             double h_s, int count, PlanExcitationScratch& scratch, Eigen::MatrixXd& out,
                             Eigen::MatrixXd* activations = nullptr, const FlatOutputStart* start = nullptr);

}  // namespace flatsos::planner
