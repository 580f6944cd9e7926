#include "flatsos/plugin/integration/closed_loop.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "flatsos/plugin/stopwatch.hpp"

namespace flatsos::plugin {

ClosedLoopResult simulate_closed_loop(const MusculoskeletalModel& plant, Controller& controller,
                                      const SimTK::State& initial, const ClosedLoopOptions& o) {
  if (!(o.duration_s > 0.0) || !std::isfinite(o.duration_s)) throw std::invalid_argument("closed loop: duration must be > 0 s");
  if (!(o.control_period_s > 0.0) || !std::isfinite(o.control_period_s))
    throw std::invalid_argument("closed loop: control period must be > 0 s");
  if (o.reports_per_period < 1) throw std::invalid_argument("closed loop: need at least one report per period");
  ClosedLoopResult out;
  out.states = make_state_table(plant, "simulation");
  out.controls = make_controls_table(plant, "simulation_controls");

  const Stopwatch wall;
  const auto stepper = make_stepper(plant, o.integrator, o.accuracy);
  stepper->initialize(initial);
  const auto append_row = [&](const SimTK::State& st) {
    append_state_row(plant, st, out.states);
    append_controls_row(plant, st, out.controls);
  };
  append_row(stepper->state());
  std::vector<double> report_times(static_cast<std::size_t>(o.reports_per_period));
  const int periods = static_cast<int>(std::ceil(o.duration_s / o.control_period_s - 1e-9));
  for (int k = 0; k < periods && out.finite; ++k) {
    // The controller changes the inputs of the integrator's own state (no copy); Simbody's
    // integrators then restart (CPodes BDF cold), the Rosenbrock method keeps its step size.
    SimTK::State& state = stepper->updState();
    plant.system().realize(state, SimTK::Stage::Acceleration);  // the measurement of qdd
    controller.control(state);
    stepper->inputsChanged();
    const double t_begin = stepper->state().getTime();
    const double t_end = initial.getTime() + std::min(o.duration_s, (k + 1) * o.control_period_s);
    for (int r = 1; r <= o.reports_per_period; ++r)
      report_times[static_cast<std::size_t>(r - 1)] = t_begin + (t_end - t_begin) * r / o.reports_per_period;
    report_times.back() = t_end;
    out.finite = stepper->advanceTo(t_end, report_times, append_row);
  }
  out.integrator_steps = stepper->stepsTaken();
  out.integrator_attempts = stepper->stepsAttempted();
  out.final_state = stepper->state();
  out.wall_seconds = std::max(wall.seconds(), 1e-9);
  out.real_time_factor = (out.final_state.getTime() - initial.getTime()) / out.wall_seconds;
  return out;
}

double settling_time(const MusculoskeletalModel& model, const StoTable& states, const Eigen::VectorXd& target,
                     double tolerance_rad, double slider_tolerance_m) {
  if (target.size() != model.numJoints()) throw std::invalid_argument("settling time: target must have one angle per joint");
  double settled = -1.0;
  for (std::size_t r = states.rows.size(); r-- > 0;) {
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
