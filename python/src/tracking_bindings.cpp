// flatsos.track: the receding-horizon controller following a measured motion (what OpenSim's CMC
// does).
#include "bindings.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "flatsos/planner/effort.hpp"
#include "flatsos/planner/rest_state.hpp"
#include "flatsos/planner/static_optimization.hpp"
#include "flatsos/planner/tracking.hpp"

namespace py = pybind11;

namespace flatsos::python {

namespace {

py::dict track(const Model& m, const std::string& motion_file, const py::object& effort, const py::object& weights,
               const py::object& plant, double horizon, double period, std::optional<double> correction, double observer_gain,
               const py::object& reserves, double cutoff_hz, double tolerance) {
  const plugin::MusculoskeletalModel& model = *m.model;
  if (!plant.is_none() && !py::isinstance<Model>(plant)) throw py::value_error("plant: expected a flatsos.Model");
  if (!(tolerance > 0.0)) throw py::value_error("tolerance: must be a positive angle, rad");
  const Model& given_plant = plant.is_none() ? m : plant.cast<const Model&>();
  const std::shared_ptr<const planner::Effort> chosen = effort_argument(effort, weights, model.numMuscles());
  planner::RecedingHorizonControllerOptions options;
  options.plan.horizon_s = horizon;
  options.plan.reserves_N = vector_argument(reserves, model.numMuscles(), "reserves", true);
  options.control_period_s = period;
  options.disturbance_observer_gain_per_s = observer_gain;

  planner::TrackingRun run;
  int steps = 0, plan_failures = 0, clamped = 0;
  std::vector<std::pair<double, std::string>> free_starts;  // periods whose plan could not start from the muscles
  {
    py::gil_scoped_release release;
    const plugin::ProcessedCoordinates motion = planner::read_motion_for(model, motion_file, cutoff_hz);
    auto reference = std::make_shared<const planner::JointReference>(planner::JointReference::fromMotion(model, motion));
    const std::vector<Eigen::VectorXd> postures = planner::reference_postures(*reference, motion.report_times_s);
    auto flat = flat_for_task(m, postures);
    // A linear effort prices the steps' LP (the map's); a nonlinear one is each step's sequential QP.
    const bool linear = chosen && chosen->tendonForceWeights();
    const planner::FlatOutputMap planning = linear ? flat->withEffort(chosen) : *flat;
    if (chosen && !linear) options.plan.effort = chosen;
    options.plan.tracking_correction_s =
        correction.value_or(std::min(planner::tracking_correction_for(options.plan.effort.get()), horizon));
    options.plan.reference = reference;
    planner::RecedingHorizonController controller(planning, options, plant.is_none() ? nullptr : given_plant.model);
    auto plant_flat = plant.is_none() ? flat : flat_for_task(given_plant, postures);
    const SimTK::State initial = planner::tracking_start_state(*plant_flat, *reference, options.plan.reserves_N);
    run = planner::run_tracking(controller, initial, planner::tracking_loop_options(), tolerance, 1e-3);
    steps = controller.steps();
    plan_failures = controller.planFailures();
    clamped = controller.clampedSamples();
    for (const auto& rec : controller.history())
      if (!rec.free_start_message.empty()) free_starts.emplace_back(rec.time_s, rec.free_start_message);
  }
  const plugin::MusculoskeletalModel& simulated = *given_plant.model;
  std::string message;
  for (const auto& f : run.failures) message += (message.empty() ? "" : "; ") + f;
  py::dict out;
  out["time"] = column_vector(run.loop.states, "time");
  out["q"] = columns_table(run.loop.states, joint_value_columns(simulated));
  out["activation"] = columns_table(run.loop.states, muscle_columns(simulated, "/activation"));
  out["excitation"] = columns_table(run.loop.controls, muscle_columns(simulated, ""));
  std::vector<std::string> error_columns(run.position_errors.columns.begin() + 1, run.position_errors.columns.end());
  out["position_error"] = columns_table(run.position_errors, error_columns);
  out["rms_error"] = run.rms_error;
  out["max_abs_error"] = run.max_abs_error;
  out["excitation_squared_integral"] = run.excitation_squared_integral;
  out["real_time_factor"] = run.loop.real_time_factor;
  out["wall_seconds"] = run.loop.wall_seconds;
  out["success"] = run.success();
  out["message"] = message;
  out["steps"] = steps;
  out["plan_failures"] = plan_failures;
  out["clamped_samples"] = clamped;
  out["free_starts"] = free_starts;
  return out;
}

}  // namespace

void register_tracking(py::module_& m) {
  m.def("track", &track, py::arg("model"), py::arg("motion_file"), py::kw_only(), py::arg("effort") = "excitation_squared",
        py::arg("weights") = py::none(), py::arg("plant") = py::none(), py::arg("horizon") = 0.5,
        py::arg("period") = 0.05, py::arg("correction") = py::none(), py::arg("observer_gain") = 40.0,
        py::arg("reserves") = 1.0, py::arg("cutoff_hz") = 6.0, py::arg("tolerance") = M_PI / 180.0,
        "The receding-horizon controller following a measured motion on a Simbody plant (what OpenSim's CMC does). "
        "The motion (an OpenSim coordinates table, .mot or .sto, degrees or radians as its header says) is filtered "
        "at `cutoff_hz` and splined as OpenSim's tools do; the plant (`plant`, a flatsos.Model with the same joints "
        "and muscles, or the model itself) starts on it at its first time with its muscles at the minimum-effort "
        "rest; every `period` s the controller plans the motion's next `horizon` s from the measured state "
        "(removing the offset within `correction` s: None is 0.06 with a squared or cubed effort, 0.075 with a "
        "linear one; starting from where the muscles are) and applies the first "
        "period's excitations. effort: what each plan minimizes over its horizon: 'excitation_squared' (the "
        "default, as CMC and Moco), 'excitation_cubed', 'activation_squared', 'activation_cubed', "
        "'stress_squared', 'stress_cubed' (weights per muscle optional), 'tendon_force' (with `weights`), or None "
        "(the model's effort_weights: the paper's linear effort). "
        "Returns a dict: 'time' (s), 'q' (rad), 'activation', 'excitation' (one row per "
        "report time), 'position_error' (reference - plant, rad), 'rms_error' and 'max_abs_error' per joint (rad), "
        "'excitation_squared_integral', 'real_time_factor', 'wall_seconds', 'success' (every plan solved, every "
        "coordinate within `tolerance` rad), 'message', 'steps', 'plan_failures', 'clamped_samples', 'free_starts' ((time, why) of each period whose plan "
        "could not start from the muscles' states and started free). Releases the GIL.");
}

}  // namespace flatsos::python
