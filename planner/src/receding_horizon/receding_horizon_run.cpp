// A receding-horizon controller's closed-loop run and what is reported of it: the settling
// times, the failures in words, the predicted joint paths.
#include <algorithm>
#include <sstream>

#include "flatsos/planner/receding_horizon_controller.hpp"
#include "flatness/input_checks.hpp"
#include "settling_tracker.hpp"

namespace flatsos::planner {

using detail::SettlingTracker;

std::vector<plugin::StoTable> prediction_tables(const RecedingHorizonController& controller) {
  const plugin::MusculoskeletalModel& model = controller.plant();
  std::vector<plugin::StoTable> out;
  const auto& history = controller.history();
  for (std::size_t k = 0; k < history.size(); ++k) {
    const PlanInUse& plan = history[k].plan;
    if (plan.empty()) continue;
    plugin::StoTable t;
    t.name = "prediction";
    t.metadata = {{"step", std::to_string(k)}, {"planned_at_s", std::to_string(history[k].time_s)}};
    t.columns = {"time"};
    for (int j = 0; j < model.numJoints(); ++j) {
      t.columns.push_back(plugin::coordinate_value_column(model, j));
      t.columns.push_back(plugin::coordinate_speed_column(model, j));
    }
    for (int i = 0; i <= 10; ++i) {
      const double tau = plan.path.duration_s * i / 10.0;
      const Jet jq = plan.path.jet(tau, 2);
      std::vector<double> row = {plan.start_time_s + tau};
      for (int j = 0; j < model.numJoints(); ++j) row.push_back(jq(j, 0)), row.push_back(jq(j, 1));
      t.rows.push_back(std::move(row));
    }
    out.push_back(std::move(t));
  }
  return out;
}

std::string plan_failures_sentence(const RecedingHorizonController& controller) {
  std::ostringstream why;
  why << controller.planFailures() << " of " << controller.steps() << " plans failed (the previous plan's tail ran instead)";
  if (controller.firstFailureTime() >= 0.0)
    why << ", the first at t = " << controller.firstFailureTime() << " s: " << controller.firstFailureMessage();
  return why.str();
}

namespace {
// The tracker of a run's settling: one window per set point (the first: the options' target
// from the start), each until the next took effect.
SettlingTracker settling_tracker(const RecedingHorizonController& controller, double start_s, double tolerance_rad) {
  std::vector<double> starts{start_s};
  std::vector<Eigen::VectorXd> targets{controller.options().plan.target_q_rad};
  for (const Setpoint& s : controller.options().setpoints) {
    starts.push_back(s.time_s);
    targets.push_back(s.target_q_rad);
  }
  return SettlingTracker(controller.plant(), std::move(starts), std::move(targets), tolerance_rad, 1e-3);
}
}  // namespace

RecedingHorizonRun run_receding_horizon(RecedingHorizonController& controller, const SimTK::State& initial,
                                        const plugin::ClosedLoopOptions& options, double settle_tolerance_rad) {
  detail::require_within_joint_ranges(controller.plant().description(), controller.plant().jointAngles(initial),
                                      "start joint angles (q0)");
  plugin::ClosedLoopOptions o = options;
  o.control_period_s = controller.options().control_period_s;
  SettlingTracker settling = settling_tracker(controller, initial.getTime(), settle_tolerance_rad);
  o.report = [&](const SimTK::State& state) {
    settling.observe(state);
    if (options.report) options.report(state);
  };
  RecedingHorizonRun run;
  run.loop = plugin::simulate_closed_loop(controller.plant(), controller, initial, o);
  run.predictions = prediction_tables(controller);
  const double end_s = run.loop.final_state.getTime();
  const Eigen::VectorXd& target = controller.targetAt(end_s);
  const auto& setpoints = controller.options().setpoints;
  constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;
  if (run.loop.stopped)
    run.failures.push_back("stopped at t = " + std::to_string(end_s) + " s of " + std::to_string(o.duration_s) +
                           " s: a stop was requested");
  if (run.loop.finite) {
    const std::vector<double> settled = settling.settledTimes();  // absolute times, -1: never
    run.settling_time_s = settled.empty() ? -1.0 : settled.back();
    if (!setpoints.empty()) {
      const double first_s = initial.getTime();
      for (std::size_t i = 0; i < settled.size(); ++i) {
        const double from = i == 0 ? first_s : setpoints[i - 1].time_s;
        run.setpoint_settling_s.push_back(settled[i] < 0.0 ? -1.0 : settled[i] - from);
      }
    }
    const auto missed = std::count(run.setpoint_settling_s.begin(), run.setpoint_settling_s.end() - (setpoints.empty() ? 0 : 1), -1.0);
    if (missed > 0)
      run.failures.push_back(std::to_string(missed) + " of " + std::to_string(setpoints.size()) +
                             " set points before the last were not reached within " +
                             std::to_string(settle_tolerance_rad * kDegPerRad) + " deg before the next one");
  }
  if (!run.loop.finite) run.failures.push_back("the simulation became non-finite");
  if (run.loop.finite && !run.loop.stopped && run.settling_time_s < 0.0) {
    const Eigen::VectorXd error = (controller.plant().jointAngles(run.loop.final_state) - target).cwiseAbs();
    double error_rad = 0.0, error_m = 0.0;  // pins', sliders'
    for (int j = 0; j < error.size(); ++j) {
      double& worst = controller.plant().description().joints[static_cast<std::size_t>(j)].isSlider() ? error_m : error_rad;
      worst = std::max(worst, error[j]);
    }
    std::ostringstream why;
    why << "never settled within " << settle_tolerance_rad * kDegPerRad << " deg of the target in " << o.duration_s
        << " s (final error " << error_rad * kDegPerRad << " deg";
    if (error_m > 0.0) why << ", " << error_m << " m along sliders";
    why << ")";
    run.failures.push_back(why.str());
  }
  if (controller.planFailures() > 0) run.failures.push_back(plan_failures_sentence(controller));
  const ControllerFaults& faults = controller.faults();
  if (!run.failures.empty() && faults.deadline_misses > 0)  // a likely cause
    run.failures.push_back(std::to_string(faults.deadline_misses) + " of " + std::to_string(controller.steps()) +
                           " plans missed their compute deadline (" + std::to_string(faults.steps_without_plan) +
                           " steps had no earlier plan to run)");
  return run;
}

std::vector<std::pair<std::string, int>> named_fault_counts(const ControllerFaults& faults,
                                                            bool integration_finite) {
  return {{"solver_failures", faults.solver_failures},
          {"non_finite_plans", faults.non_finite_plans},
          {"non_finite_measurements", faults.non_finite_measurements},
          {"deadline_misses", faults.deadline_misses},
          {"steps_without_plan", faults.steps_without_plan},
          {"integrator_failures", integration_finite ? 0 : 1}};
}

}  // namespace flatsos::planner
