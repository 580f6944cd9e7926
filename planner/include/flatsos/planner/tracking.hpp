#pragma once
// Tracking a joint motion with the receding-horizon controller (what OpenSim's CMC and Moco's
// MocoTrack do for a measured motion): the controller's options carry the reference
// (RecedingHorizonOptions::reference), each step plans the reference over its horizon plus a
// correction from the measured state, and the run reports the errors as CMC writes them.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there

#include <string>
#include <vector>

#include "flatsos/planner/receding_horizon_controller.hpp"

namespace flatsos::planner {

struct TrackingRun {
  plugin::ClosedLoopResult loop;
  /// CMC's position errors: per report time of loop.states, reference - plant per coordinate
  /// (columns named by the coordinates, rad or m).
  plugin::StoTable position_errors;
  Eigen::VectorXd rms_error, max_abs_error;  ///< per joint over those times: rad (a slider's m)
  double excitation_squared_integral = 0.0;  ///< the integral of sum_j u_j^2 dt (controller's)
  /// Why the task failed, one sentence each: the run became non-finite, some plans failed, or a
  /// coordinate left the reference by more than the tolerance. Empty: it succeeded.
  std::vector<std::string> failures;
  bool success() const { return failures.empty(); }
};

/// Runs a controller that tracks a reference (options().plan.reference) on its plant from
/// `initial` to the reference's end time (options.duration_s is set from there). Failure beyond
/// tolerance_rad on a pin or tolerance_m on a slider at any report time. Throws
/// std::invalid_argument for a controller without a reference or an initial time not before the
/// reference's end.
TrackingRun run_tracking(RecedingHorizonController& controller, const SimTK::State& initial,
                         const plugin::ClosedLoopOptions& options,
                         double tolerance_rad = 3.14159265358979323846 / 180.0, double tolerance_m = 1e-3);

/// What a tracking run is set up with (the programs, flatsos.track, the bench and the tests alike):
/// the postures the reference visits at `times_s` (to choose flat outputs over:
/// flat_outputs_for_task).
std::vector<Eigen::VectorXd> reference_postures(const JointReference& reference, const std::vector<double>& times_s);
/// The plant's state on the reference at its first time (position and speed), its muscles at the
/// minimum-effort rest there with `reserves_N` (start_state), the time set.
SimTK::State tracking_start_state(const FlatOutputMap& plant_flat, const JointReference& reference,
                                  const Eigen::VectorXd& reserves_N);
/// The closed loop's simulation: each muscle integrated on its own (MuscleRosenbrock) to 1e-5.
plugin::ClosedLoopOptions tracking_loop_options();
/// The correction time the programs track with (RecedingHorizonOptions::tracking_correction_s)
/// when none is given: 0.06 s for a nonlinear effort (on arm26 it holds plants 20 % weaker or
/// stronger), the library's 0.075 s for the paper's linear one (null), which failed 11 of 20
/// plans at 0.06 s on the paper's arm with uneven strengths.
double tracking_correction_for(const Effort* effort);

}  // namespace flatsos::planner
