#pragma once
// A closed-loop simulation harness: a controller changes the muscles' inputs at the start of
// every control period, one of the steppers of stepper.hpp integrates in between. It knows
// nothing of how the controller decides (the planner's receding-horizon controller is one).

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <Simbody.h>

#include <Eigen/Core>
#include <atomic>
#include <functional>

#include "flatsos/plugin/integration/joint_sensors.hpp"
#include "flatsos/plugin/integration/stepper.hpp"
#include "flatsos/plugin/io/state_table.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace flatsos::plugin {

/// What a closed loop calls every control period.
class Controller {
 public:
  virtual ~Controller() = default;
  /// Changes the inputs (excitations, discrete variables) of `state` for the next period, from
  /// what the sensors measured (`measured`, the joints as ClosedLoopOptions::sensors give them).
  /// `state` is the stepper's own state at the control time: change its inputs, do not keep it
  /// and do not read the joints from it (that is the sensors' work).
  virtual void control(SimTK::State& state, const JointMeasurement& measured) = 0;
};

struct ClosedLoopOptions {
  double duration_s = 2.0;
  double control_period_s = 0.05;
  IntegratorKind integrator = IntegratorKind::RungeKuttaMerson;
  double accuracy = 1e-8;      ///< relative, the stepper's meaning
  int reports_per_period = 5;  ///< rows of the state table per period
  SensorOptions sensors;       ///< noise and delay of the joint measurements (default: exact)
  /// The controller's inputs reach the muscles this much later (ActuationDelay; 0: at once).
  double actuation_delay_s = 0.0;
  /// Called with the state at every report time (the start's included), in order: a long run
  /// streams its rows from here instead of keeping the tables.
  std::function<void(const SimTK::State&)> report;
  bool keep_tables = true;  ///< false: ClosedLoopResult's tables stay empty (memory stays flat)
  /// Set (by a signal handler, say) to end the run at the next control time: ClosedLoopResult
  /// says it stopped, and its tables and final state are the run up to there.
  const std::atomic<bool>* stop = nullptr;
};

struct ClosedLoopResult {
  StoTable states;                ///< make_state_table columns, one row at the start and reports_per_period per period
  StoTable controls;              ///< make_controls_table columns, the same times (the excitation in effect there)
  SimTK::State final_state;
  bool finite = true;             ///< false: a state became NaN/Inf or the integrator could not continue; the run stopped there
  bool stopped = false;           ///< ClosedLoopOptions::stop ended the run before its duration
  double wall_seconds = 0.0;      ///< controller and integration
  double real_time_factor = 0.0;  ///< simulated time / wall time
  long integrator_steps = 0;
  long integrator_attempts = 0;   ///< steps tried, rejected ones included
};

/// Runs `controller` on `plant` from `initial`. The controller acts at initial time + k period
/// (k = 0, 1, ...) on the stepper's own state; the muscle Rosenbrock method keeps its step size
/// across these input changes, Simbody's integrators restart. Throws std::invalid_argument for a
/// non-positive duration or period, reports_per_period < 1, or a sensor or actuation delay that
/// is negative.
ClosedLoopResult simulate_closed_loop(const MusculoskeletalModel& plant, Controller& controller,
                                      const SimTK::State& initial, const ClosedLoopOptions& options);

/// The first time of `states` (a make_state_table of `model`) in [from_s, to_s) from which every
/// pin stays within `tolerance_rad` and every slider within `slider_tolerance_m` of
/// `target_q_rad` until the last row before to_s; -1 when that row is outside (or none is in
/// the window).
double settling_time(const MusculoskeletalModel& model, const StoTable& states, const Eigen::VectorXd& target_q_rad,
                     double tolerance_rad, double slider_tolerance_m = 1e-3, double from_s = -1e300,
                     double to_s = 1e300);

}  // namespace flatsos::plugin
