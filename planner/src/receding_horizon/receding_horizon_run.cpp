// A receding-horizon controller's closed-loop run and what is reported of it: the settling
// times, the failures in words, the predicted joint paths.
#include <algorithm>
#include <sstream>

#include "flatsos/planner/receding_horizon_controller.hpp"
#include "flatness/input_checks.hpp"

namespace flatsos::planner {

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
  const auto& history = controller.history();
  const auto first = std::find_if(history.begin(), history.end(),
                                  [](const RecedingHorizonRecord& r) { return r.status != SolveStatus::Solved; });
  if (first != history.end()) why << ", the first at t = " << first->time_s << " s: " << first->message;
  return why.str();
}

namespace {
// Per set point (the first: the options' target from the start), when after it the joints
// settled within the tolerance until the next one took effect (-1: never).
std::vector<double> setpoint_settling_times(const RecedingHorizonController& controller, const plugin::StoTable& states,
                                            double tolerance_rad, double end_s) {
  const auto& setpoints = controller.options().setpoints;
  if (setpoints.empty()) return {};
  std::vector<double> out;
  double from = states.rows.empty() ? 0.0 : states.rows.front()[0];
  for (std::size_t i = 0; i <= setpoints.size(); ++i) {
    const double to = i < setpoints.size() ? setpoints[i].time_s : end_s + 1.0;
    if (from > end_s) break;  // set points after the run's end
    const Eigen::VectorXd& target = i == 0 ? controller.options().plan.target_q_rad : setpoints[i - 1].target_q_rad;
    const double settled = plugin::settling_time(controller.plant(), states, target, tolerance_rad, 1e-3, from, to);
    out.push_back(settled < 0.0 ? -1.0 : settled - from);
    from = to;
  }
  return out;
}
}  // namespace

RecedingHorizonRun run_receding_horizon(RecedingHorizonController& controller, const SimTK::State& initial,
                                        const plugin::ClosedLoopOptions& options, double settle_tolerance_rad) {
  detail::require_within_joint_ranges(controller.plant().description(), controller.plant().jointAngles(initial),
                                      "start joint angles (q0)");
  plugin::ClosedLoopOptions o = options;
  o.control_period_s = controller.options().control_period_s;
  RecedingHorizonRun run;
  run.loop = plugin::simulate_closed_loop(controller.plant(), controller, initial, o);
  run.predictions = prediction_tables(controller);
  const double end_s = run.loop.final_state.getTime();
  const Eigen::VectorXd& target = controller.targetAt(end_s);
  const auto& setpoints = controller.options().setpoints;
  const double last_change_s = setpoints.empty() ? -1e300 : setpoints.back().time_s;
  constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;
  if (run.loop.finite) {
    run.settling_time_s = plugin::settling_time(controller.plant(), run.loop.states, target, settle_tolerance_rad, 1e-3,
                                                last_change_s);
    run.setpoint_settling_s = setpoint_settling_times(controller, run.loop.states, settle_tolerance_rad, end_s);
    const auto missed = std::count(run.setpoint_settling_s.begin(), run.setpoint_settling_s.end() - (setpoints.empty() ? 0 : 1), -1.0);
    if (missed > 0)
      run.failures.push_back(std::to_string(missed) + " of " + std::to_string(setpoints.size()) +
                             " set points before the last were not reached within " +
                             std::to_string(settle_tolerance_rad * kDegPerRad) + " deg before the next one");
  }
  if (!run.loop.finite) run.failures.push_back("the simulation became non-finite");
  if (run.loop.finite && run.settling_time_s < 0.0) {
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

}  // namespace flatsos::planner
