#include "flatsos/plugin/integration/closed_loop.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "flatsos/plugin/integration/actuation_delay.hpp"
#include "flatsos/plugin/stopwatch.hpp"

namespace flatsos::plugin {

namespace {

constexpr double kMaxPeriods = 1e9;  // 1.6 years at 50 ms

// Advances `stepper` to t_end through `times` (see Stepper::advanceTo), stopping where a delayed
// command reaches the muscles before t_end to set it (one due at t_end is set at the next
// control time, before the controller acts).
bool advance_with_commands_due(Stepper& stepper, ActuationDelay& actuation, double t_end,
                               const std::vector<double>& times, std::vector<double>& segment_times,
                               const Stepper::Report& report) {
  auto next = times.begin();
  while (actuation.nextDue() < t_end - 1e-9) {
    const double due = std::max(actuation.nextDue(), stepper.state().getTime());
    segment_times.clear();
    for (; next != times.end() && *next <= due; ++next) segment_times.push_back(*next);
    if (!stepper.advanceTo(due, segment_times, report)) return false;
    actuation.applyDue(stepper.updState());
    stepper.inputsChanged();
  }
  segment_times.assign(next, times.end());
  return stepper.advanceTo(t_end, segment_times, report);
}

}  // namespace

ClosedLoopResult simulate_closed_loop(const MusculoskeletalModel& plant, Controller& controller,
                                      const SimTK::State& initial, const ClosedLoopOptions& o) {
  if (!(o.duration_s > 0.0) || !std::isfinite(o.duration_s)) throw std::invalid_argument("closed loop: duration must be > 0 s");
  if (!(o.control_period_s > 0.0) || !std::isfinite(o.control_period_s))
    throw std::invalid_argument("closed loop: control period must be > 0 s");
  if (o.reports_per_period < 1) throw std::invalid_argument("closed loop: need at least one report per period");
  if (o.duration_s / o.control_period_s > kMaxPeriods)  // the period count must fit an int
    throw std::invalid_argument("closed loop: a duration of " + std::to_string(o.duration_s) + " s is more than " +
                                std::to_string(static_cast<long>(kMaxPeriods)) + " control periods");
  ClosedLoopResult out;
  out.states = make_state_table(plant, "simulation");
  out.controls = make_controls_table(plant, "simulation_controls");

  const Stopwatch wall;
  const auto stepper = make_stepper(plant, resolve_integrator(plant, initial, o.duration_s, o.integrator), o.accuracy);
  stepper->initialize(initial);
  const auto append_row = [&](const SimTK::State& st) {
    if (o.keep_tables) {
      append_state_row(plant, st, out.states);
      append_controls_row(plant, st, out.controls);
    }
    if (o.report) o.report(st);
  };
  append_row(stepper->state());
  JointSensors sensors(plant, o.sensors, o.control_period_s, initial.getTime());
  sensors.take(stepper->state());
  ActuationDelay actuation(plant, o.actuation_delay_s, o.control_period_s);
  const bool delayed = o.sensors.delay_s > 0.0;
  // Each period's report times, the sensors' sample times, and both merged (reused storage).
  std::vector<double> report_times(static_cast<std::size_t>(o.reports_per_period)), sample_times, times,
      segment_times;
  const auto report_or_sample = [&](const SimTK::State& st) {
    const double t = st.getTime();
    if (std::binary_search(report_times.begin(), report_times.end(), t)) append_row(st);
    if (std::binary_search(sample_times.begin(), sample_times.end(), t)) sensors.take(st);
  };
  const int periods = static_cast<int>(std::ceil(o.duration_s / o.control_period_s - 1e-9));
  for (int k = 0; k < periods && out.finite; ++k) {
    if (o.stop && o.stop->load()) {
      out.stopped = true;
      break;
    }
    // The controller changes the inputs of the integrator's own state (no copy); Simbody's
    // integrators then restart (CPodes BDF cold), the Rosenbrock method keeps its step size.
    SimTK::State& state = stepper->updState();
    const double t_begin = state.getTime();
    if (!delayed && k > 0) sensors.take(state);  // (the start's was taken above)
    if (actuation.active()) {
      actuation.applyDue(state);
      actuation.keepInputsInEffect(state);
    }
    controller.control(state, sensors.read(t_begin));
    if (actuation.active()) actuation.holdBack(state);
    stepper->inputsChanged();
    const double t_end = initial.getTime() + std::min(o.duration_s, (k + 1) * o.control_period_s);
    for (int r = 1; r <= o.reports_per_period; ++r)
      report_times[static_cast<std::size_t>(r - 1)] = t_begin + (t_end - t_begin) * r / o.reports_per_period;
    report_times.back() = t_end;
    sample_times.clear();
    sensors.sampleTimes(t_begin, t_end, sample_times);
    // A sample due at a report time (to rounding) is taken there: no step of a few ulps between.
    for (double& s : sample_times)
      for (const double r : report_times)
        if (std::abs(s - r) < 1e-9) s = r;
    times.clear();
    std::set_union(report_times.begin(), report_times.end(), sample_times.begin(), sample_times.end(),
                   std::back_inserter(times));
    out.finite = advance_with_commands_due(*stepper, actuation, t_end, times, segment_times, report_or_sample);
  }
  out.integrator_steps = stepper->stepsTaken();
  out.integrator_attempts = stepper->stepsAttempted();
  out.final_state = stepper->state();
  out.wall_seconds = std::max(wall.seconds(), 1e-9);
  out.real_time_factor = (out.final_state.getTime() - initial.getTime()) / out.wall_seconds;
  return out;
}

double settling_time(const MusculoskeletalModel& model, const StoTable& states, const Eigen::VectorXd& target,
                     double tolerance_rad, double slider_tolerance_m, double from_s, double to_s) {
  if (target.size() != model.numJoints()) throw std::invalid_argument("settling time: target must have one angle per joint");
  double settled = -1.0;
  for (std::size_t r = states.rows.size(); r-- > 0;) {
    const double t = states.rows[r][0];
    if (t >= to_s) continue;
    if (t < from_s) break;
    bool inside = true;
    for (int j = 0; j < model.numJoints(); ++j) {  // columns: time, then q and qdot per joint
      const double tolerance = model.description().joints[static_cast<std::size_t>(j)].isSlider() ? slider_tolerance_m : tolerance_rad;
      inside = inside && std::abs(states.rows[r][static_cast<std::size_t>(1 + 2 * j)] - target[j]) <= tolerance;
    }
    if (!inside) break;
    settled = states.rows[r][0];
  }
  return settled;
}

}  // namespace flatsos::plugin
