#pragma once
// The receding-horizon (RH) controller of the paper, plugged into Simbody through the muscles'
// excitation inputs. Every control period delta: read q, qd from the State, plan one RH step
// (cubic to the target over the horizon, torque box, SLP), evaluate the plan's excitations on the
// first period by the exact inverse map, and give each muscle a piecewise-linear signal over
// [t, t + delta]. Excitations outside [0, 1] are clamped (by the muscle) and counted here.
// A failed plan never stops the loop: the previous plan's tail is used and the failure recorded.

#include <functional>
#include <string>
#include <vector>

#include <Simbody.h>

#include "flatsos/planner/motion_planner.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"

namespace flatsos::planner {

/// The planning step a controller calls; replaceable (another planner, or fault injection in
/// tests). Default: plan_receding_horizon_step.
using RecedingHorizonPlanner = std::function<RecedingHorizonStep(const FlatOutputMap&, const Eigen::VectorXd& q_rad,
                                                                 const Eigen::VectorXd& qd_rad_per_s,
                                                                 const RecedingHorizonOptions&)>;

struct RecedingHorizonControllerOptions {
  RecedingHorizonOptions plan;             ///< horizon, grid, target, reserves, SLP solver
  RecedingHorizonPlanner planner = plan_receding_horizon_step;
  double control_period_s = 0.05;          ///< delta
  int excitation_samples_per_period = 11;  ///< inverse-map samples per period (fitted by a polynomial)
  /// Disturbance observer with integral action: every step, the joint torque the plant did not
  /// deliver is measured as the prediction error of the plan in use, e = ID(q, qd, qdd) measured
  /// - ID(q, qd, qdd) that plan predicted for now (its muscles were asked for the latter), and
  /// integrated, d += gain e; the next plan asks the muscles for ID(path) - d. A rest away from
  /// the target leaves the plan asking for acceleration the arm does not show, so d keeps
  /// moving: no offset. Gains 0.5-2 measured stable on the arm (1 recommended); 0 disables it
  /// (the paper's controller).
  double disturbance_observer_gain = 0.0;
};

struct RecedingHorizonRecord {
  double time_s = 0.0;
  SolveStatus status = SolveStatus::Failed;
  std::string message;
  bool used_previous_plan = false;  ///< this step failed and ran on the previous plan's tail
  Eigen::VectorXd alpha;            ///< constant Y of the plan in use
  JointPath path;                   ///< predicted joint motion of the plan in use
  double plan_start_time_s = 0.0;   ///< simulation time of that plan's t = 0
  int clamped_samples = 0;          ///< excitation samples outside [0, 1] this period
  double plan_seconds = 0.0;        ///< the SLP step
  double step_seconds = 0.0;        ///< plan + excitations
  Eigen::VectorXd torque_offset_N_m;  ///< the observer's estimate used by this step's plan
};

class RecedingHorizonController {
 public:
  /// Throws std::invalid_argument for a non-positive period, fewer than 2 samples or bad plan
  /// options (checked on the first step).
  RecedingHorizonController(const FlatOutputMap& flat, RecedingHorizonControllerOptions options);

  /// Plans from the state at its time and installs the excitation signals for the next period.
  const RecedingHorizonRecord& step(SimTK::State& state);
  /// Same for a plant that is a different model from the planner's (same joints and muscles in
  /// the same order, other parameters): measures on and drives `plant`.
  const RecedingHorizonRecord& step(const plugin::MusculoskeletalModel& plant, SimTK::State& state);

  const std::vector<RecedingHorizonRecord>& history() const { return history_; }
  int planFailures() const;
  int clampedSamples() const;
  const RecedingHorizonControllerOptions& options() const { return options_; }
  const FlatOutputMap& flat() const { return flat_; }

 private:
  const FlatOutputMap& flat_;
  RecedingHorizonControllerOptions options_;
  std::vector<RecedingHorizonRecord> history_;
  Eigen::VectorXd torque_offset_;  ///< the disturbance observer's state
};

/// A closed-loop run: the controller plans every period, Simbody integrates in between.
struct ClosedLoopResult {
  plugin::StoTable states;       ///< plugin::make_state_table columns, `reports_per_period` rows per period
  plugin::StoTable predictions;  ///< time, /controller/step, /jointset/<joint>/q_predicted (11 per step)
  SimTK::State final_state;
  bool finite = true;            ///< false: a state became NaN/Inf, or the integrator could not continue; the run stopped there
  double settling_time_s = -1;   ///< every joint within `settle_tolerance_rad` of the target from then on; -1: never
  double wall_seconds = 0.0;
  double real_time_factor = 0.0;  ///< simulated time / wall time
  long integrator_steps = 0;
  long integrator_attempts = 0;  ///< steps tried, rejected ones included
};

/// Runs `controller` on the model's Simbody system from `initial` for `duration_s` with the
/// integrator `integrator` at `accuracy` (see plugin/stepper.hpp; the muscle Rosenbrock method
/// keeps its step size across the controller's input changes, Simbody's integrators restart).
ClosedLoopResult simulate_closed_loop(RecedingHorizonController& controller, const SimTK::State& initial,
                                      double duration_s, double accuracy = 1e-8, int reports_per_period = 5,
                                      double settle_tolerance_rad = 3.14159265358979323846 / 180.0,
                                      plugin::IntegratorKind integrator = plugin::IntegratorKind::RungeKuttaMerson);
/// The same with a plant model other than the planner's (model mismatch studies).
ClosedLoopResult simulate_closed_loop(RecedingHorizonController& controller, const plugin::MusculoskeletalModel& plant,
                                      const SimTK::State& initial, double duration_s, double accuracy = 1e-8,
                                      int reports_per_period = 5,
                                      double settle_tolerance_rad = 3.14159265358979323846 / 180.0,
                                      plugin::IntegratorKind integrator = plugin::IntegratorKind::RungeKuttaMerson);

/// Minimum-effort static equilibrium at joint angles q: the SLP with the target at q gives the
/// constant flat outputs; the inverse map at rest gives tendon lengths and activations (u = 0).
/// Sets q, qd = 0, L_S, a and held excitations n = a on the state.
void set_minimum_effort_rest_state(const FlatOutputMap& flat, SimTK::State& state, const Eigen::VectorXd& q_rad,
                                   const Eigen::VectorXd& reserves_N);

}  // namespace flatsos::planner
