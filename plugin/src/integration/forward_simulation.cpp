#include "flatsos/plugin/integration/forward_simulation.hpp"

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

namespace flatsos::plugin {

namespace {
constexpr double kMaxReports = 1e8;  // rows of a table: 1e8 rows of the arm's are some 30 GB
}  // namespace

bool all_states_finite(const SimTK::State& s) {
  const SimTK::Vector& y = s.getY();
  for (int i = 0; i < y.size(); ++i)
    if (!std::isfinite(y[i])) return false;
  return true;
}

SimulationResult simulate(const MusculoskeletalModel& model, const SimTK::State& initial,
                          const SimulationOptions& o) {
  if (!(o.duration_s > 0.0) || !std::isfinite(o.duration_s))
    throw std::invalid_argument("simulation duration must be a finite number > 0 s");
  if (!(o.accuracy > 0.0 && o.accuracy < 1.0))
    throw std::invalid_argument("integrator accuracy must be in (0, 1)");
  if (!(o.report_interval_s > 0.0) || !std::isfinite(o.report_interval_s))
    throw std::invalid_argument("report interval must be a finite number > 0 s");
  if (o.max_steps < 0) throw std::invalid_argument("simulation max_steps must be >= 0 (0: no limit)");
  if (!all_states_finite(initial))
    throw std::invalid_argument("initial state has a non-finite value");

  SimulationResult result;
  result.states = make_state_table(model);
  result.controls = make_controls_table(model);
  result.integrator = resolve_integrator(model, initial, o.duration_s, o.integrator);
  const auto stepper = make_stepper(model, result.integrator, o.accuracy);
  stepper->initialize(initial);
  const double t0 = initial.getTime(), t_end = t0 + o.duration_s;
  const auto append_rows = [&](const SimTK::State& s) {
    append_state_row(model, s, result.states);
    append_controls_row(model, s, result.controls);
  };
  append_rows(stepper->state());

  if (o.duration_s / o.report_interval_s > kMaxReports)
    throw std::invalid_argument("simulation: a duration of " + std::to_string(o.duration_s) + " s reported every " +
                                std::to_string(o.report_interval_s) + " s is more than 1e8 rows");
  stepper->setStepLimit(o.max_steps);  // at the end the run is complete, however many steps it took
  const auto reports = static_cast<long>(std::ceil(o.duration_s / o.report_interval_s - 1e-9));
  std::vector<double> times;
  for (long k = 1; k <= reports; ++k) times.push_back(t0 + std::min(o.duration_s, static_cast<double>(k) * o.report_interval_s));
  const bool reached_the_end = stepper->advanceTo(t_end, times, append_rows);
  if (!reached_the_end && !stepper->stepLimitReached()) {
    result.finite = false;
    result.message = "integration stopped at t = " + std::to_string(stepper->state().getTime()) +
                     " s: a state became non-finite or the step size collapsed";
  } else if (!reached_the_end) {
    append_rows(stepper->state());  // the tables end where the run stopped
    result.step_limit_reached = true;
    result.message = "integration stopped at t = " + std::to_string(stepper->state().getTime()) + " s of " +
                     std::to_string(t_end) + " s after " + std::to_string(stepper->stepsTaken()) +
                     " steps, the step limit";
    if (result.integrator == IntegratorKind::RungeKuttaMerson)
      result.message += ": the explicit Runge-Kutta-Merson method takes tiny steps where the muscles' states are "
                        "stiff (a tendon loaded at tiny activation); the implicit rosenbrock or bdf integrators take "
                        "far fewer";
  }
  result.final_state = stepper->state();
  result.integrator_steps = stepper->stepsTaken();
  return result;
}

}  // namespace flatsos::plugin
