#include "flatsos/planner/tracking.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "flatsos/planner/rest_state.hpp"

namespace flatsos::planner {

namespace {

// Position errors (reference - plant) at every row of a state table, and their RMS and maximum.
void measure_errors(const plugin::MusculoskeletalModel& model, const JointReference& reference, TrackingRun& run) {
  const int n = model.numJoints();
  plugin::StoTable& table = run.position_errors;
  table.name = "pErr";
  table.columns = {"time"};
  for (const auto& joint : model.description().joints) table.columns.push_back(joint.coordinateName());
  run.rms_error.setZero(n);
  run.max_abs_error.setZero(n);
  for (const auto& row : run.loop.states.rows) {
    std::vector<double> errors = {row[0]};
    for (int j = 0; j < n; ++j) {  // state columns: time, then value and speed per joint
      const double e = reference.derivative(j, row[0], 0) - row[static_cast<std::size_t>(1 + 2 * j)];
      errors.push_back(e);
      run.rms_error[j] += e * e;
      run.max_abs_error[j] = std::max(run.max_abs_error[j], std::abs(e));
    }
    table.rows.push_back(std::move(errors));
  }
  if (!table.rows.empty()) run.rms_error = (run.rms_error / static_cast<double>(table.rows.size())).cwiseSqrt();
}

}  // namespace

TrackingRun run_tracking(RecedingHorizonController& controller, const SimTK::State& initial,
                         const plugin::ClosedLoopOptions& options, double tolerance_rad, double tolerance_m) {
  const std::shared_ptr<const JointReference>& reference = controller.options().plan.reference;
  if (!reference) throw std::invalid_argument("tracking: the controller has no reference to track");
  if (!(tolerance_rad > 0.0) || !(tolerance_m > 0.0))
    throw std::invalid_argument("tracking: the tolerances (rad, m) must be positive numbers");
  plugin::ClosedLoopOptions o = options;
  o.control_period_s = controller.options().control_period_s;
  o.duration_s = reference->endTime_s() - initial.getTime();
  if (!(o.duration_s > 0.0))
    throw std::invalid_argument("tracking: the run starts at or after the reference's end time");
  TrackingRun run;
  run.loop = plugin::simulate_closed_loop(controller.plant(), controller, initial, o);
  run.excitation_squared_integral = controller.excitationSquaredIntegral();
  measure_errors(controller.plant(), *reference, run);

  if (!run.loop.finite) run.failures.push_back("the simulation became non-finite");
  if (controller.planFailures() > 0) run.failures.push_back(plan_failures_sentence(controller));
  constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;
  const auto& joints = controller.plant().description().joints;
  for (int j = 0; j < run.max_abs_error.size(); ++j) {
    const bool slider = joints[static_cast<std::size_t>(j)].isSlider();
    if (run.max_abs_error[j] <= (slider ? tolerance_m : tolerance_rad)) continue;
    std::ostringstream why;
    why << "'" << joints[static_cast<std::size_t>(j)].coordinateName() << "' left the reference by "
        << (slider ? run.max_abs_error[j] : run.max_abs_error[j] * kDegPerRad) << (slider ? " m" : " deg")
        << " (tolerance " << (slider ? tolerance_m : tolerance_rad * kDegPerRad) << (slider ? " m)" : " deg)");
    run.failures.push_back(why.str());
  }
  return run;
}

std::vector<Eigen::VectorXd> reference_postures(const JointReference& reference, const std::vector<double>& times_s) {
  std::vector<Eigen::VectorXd> postures;
  postures.reserve(times_s.size());
  for (double t : times_s) postures.push_back(reference.jet(t, 1).col(0));
  return postures;
}

SimTK::State tracking_start_state(const FlatOutputMap& plant_flat, const JointReference& reference,
                                  const Eigen::VectorXd& reserves_N) {
  const double t0 = reference.startTime_s();
  const Jet start = reference.jet(t0, 2);
  // The rest at the motion's first frame, which may lie a little outside a joint's range (a
  // measured motion is not clamped to the model's ranges; start_state would refuse it).
  SimTK::State s = plant_flat.model().defaultState();
  set_minimum_effort_rest_state(plant_flat, s, start.col(0), reserves_N);
  plant_flat.model().setJointSpeeds(s, start.col(1));
  s.setTime(t0);
  return s;
}

double tracking_correction_for(const Effort* effort) {
  return effort && !effort->tendonForceWeights() ? 0.06 : RecedingHorizonOptions{}.tracking_correction_s;
}

plugin::ClosedLoopOptions tracking_loop_options() {
  plugin::ClosedLoopOptions loop;
  loop.integrator = plugin::IntegratorKind::MuscleRosenbrock;
  loop.accuracy = 1e-5;
  return loop;
}

}  // namespace flatsos::planner
