// flatsos.run_receding_horizon: the closed loop (the controller on a Simbody plant).
#include "bindings.hpp"

#include "flatsos/plugin/io/disturbance_file.hpp"

#include <cmath>
#include <string>

#include "flatsos/planner/receding_horizon_controller.hpp"
#include "flatsos/planner/receding_horizon_study.hpp"
#include "flatsos/planner/rest_state.hpp"
#include "flatsos/plugin/integration/stepper.hpp"

namespace py = pybind11;

namespace flatsos::python {

namespace {

planner::SlpSolver slp_solver_from_name(const std::string& name) {
  if (name == "exact" || name == "ipopt") return planner::SlpSolver::VertexEnumeration;
  if (name == "simplex") return planner::SlpSolver::Simplex;
  throw py::value_error("solver: unknown SLP solver '" + name + "' (exact, simplex or ipopt)");
}

struct TimedRow {
  double time_s;
  Eigen::VectorXd values;
};

// `rows`: the argument `what` (e.g. "setpoints"), a sequence of (time_s, `values` per joint).
std::vector<TimedRow> timed_rows(const py::object& rows, Eigen::Index joints, const std::string& what,
                                 const std::string& values) {
  std::vector<TimedRow> out;
  const std::string shape = what + ": a sequence of (time_s, " + values + " per joint)";
  if (!py::isinstance<py::sequence>(rows)) throw py::value_error(shape);
  for (const py::handle row : rows) {
    if (!py::isinstance<py::sequence>(row) || py::len(row) != 2) throw py::value_error(shape);
    const auto pair = py::reinterpret_borrow<py::sequence>(row);
    TimedRow r;
    try {
      r.time_s = py::cast<double>(pair[0]);
    } catch (const py::cast_error&) {
      throw py::value_error(what + ": a row's time is not a number");
    }
    r.values = vector_argument(pair[1], joints, what + " " + values);
    out.push_back(std::move(r));
  }
  return out;
}

// The model with `rows` of (time_s, forces per joint: N m, N along a slider) acting on its
// joints, each held until the next row.
std::shared_ptr<const plugin::MusculoskeletalModel> with_disturbance(const plugin::MusculoskeletalModel& model,
                                                                     const py::object& rows) {
  const std::vector<TimedRow> timed = timed_rows(rows, model.numJoints(), "disturbance", "forces");
  std::vector<double> times_s;
  Eigen::MatrixXd table(static_cast<Eigen::Index>(timed.size()), model.numJoints());
  for (std::size_t k = 0; k < timed.size(); ++k) {
    times_s.push_back(timed[k].time_s);
    table.row(static_cast<Eigen::Index>(k)) = timed[k].values.transpose();
  }
  plugin::ModelDescription d = model.description();
  auto torques = plugin::disturbance_torques(d, times_s, table);  // std::invalid_argument: ValueError
  return std::make_shared<const plugin::MusculoskeletalModel>(std::move(d), std::move(torques));
}

// setpoints: a sequence of (time_s, target_rad per joint), ascending times.
std::vector<planner::Setpoint> setpoints_argument(const py::object& rows, Eigen::Index joints) {
  std::vector<planner::Setpoint> out;
  if (rows.is_none()) return out;
  for (TimedRow& r : timed_rows(rows, joints, "setpoints", "target"))
    out.push_back({r.time_s, std::move(r.values)});
  return out;
}

// What the sensors, deadlines and set points did, as the program's summary names it.
void add_real_time_report(py::dict& out, const planner::RecedingHorizonController& controller,
                          const planner::RecedingHorizonRun& run) {
  const planner::ControllerFaults& f = controller.faults();
  out["deadline_misses"] = f.deadline_misses;
  out["longest_deadline_miss_run"] = f.longest_miss_run;
  out["worst_step_seconds"] = controller.worstStepSeconds();
  out["fallbacks"] = f.fallbacks;
  py::dict faults;
  for (const auto& [name, count] : planner::named_fault_counts(f, run.loop.finite)) faults[name.c_str()] = count;
  out["faults"] = faults;
  py::list settling;
  for (const double s : run.setpoint_settling_s) settling.append(s >= 0.0 ? py::object(py::float_(s)) : py::object(py::none()));
  out["setpoint_settling"] = settling;
}

py::dict run_receding_horizon(const Model& m, const py::object& q0, const py::object& target, double duration,
                              const py::object& qd0, const py::object& a0, const py::object& reserves, double horizon,
                              int grid_points, double period, const std::string& solver, bool bounds,
                              double observer_gain, double quick_arrival, const std::string& integrator, const py::object& accuracy,
                              const py::object& plant, double settle_tolerance, const py::object& disturbance,
                              double noise_deg, double noise_deg_per_s, unsigned seed, double measurement_delay,
                              double actuation_delay, double deadline, double inject_deadline_misses, const py::object& setpoints) {
  const plugin::MusculoskeletalModel& model = *m.model;
  const Eigen::Index joints = model.numJoints(), muscles = model.numMuscles();
  const Eigen::VectorXd q0_rad = vector_argument(q0, joints, "q0"), target_rad = vector_argument(target, joints, "target");
  const Eigen::VectorXd qd0_rad_per_s = qd0.is_none() ? Eigen::VectorXd::Zero(joints) : vector_argument(qd0, joints, "qd0");
  const Eigen::VectorXd reserves_N = vector_argument(reserves, muscles, "reserves", true);
  const std::optional<Eigen::VectorXd> activations = activations_argument(a0, muscles);
  if (!(duration > 0.0) || !std::isfinite(duration)) throw py::value_error("duration: must be a positive number of seconds");
  if (!(settle_tolerance > 0.0)) throw py::value_error("settle_tolerance: must be a positive angle, rad");

  planner::RecedingHorizonControllerOptions options;
  options.plan.horizon_s = horizon;
  options.plan.grid_points = grid_points;
  options.plan.target_q_rad = target_rad;
  options.plan.reserves_N = reserves_N;
  options.plan.solver = slp_solver_from_name(solver);
  if (solver == "ipopt")  // the interior-point reference, through the controller's planner seam
    options.planner = [](const planner::FlatOutputMap& f, plugin::ModelWorkspace& w, const Eigen::VectorXd& q,
                         const Eigen::VectorXd& qd, const planner::RecedingHorizonOptions& o,
                         planner::RecedingHorizonStep& out) {
      planner::RecedingHorizonStudyOptions by_ipopt;
      by_ipopt.slp_by_ipopt = true;
      planner::plan_receding_horizon_step(f, w, q, qd, o, by_ipopt, out);
    };
  options.plan.excitation_bounds.enforce = bounds;
  options.control_period_s = period;
  options.disturbance_observer_gain_per_s = observer_gain;
  options.quick_arrival_fraction = quick_arrival;  // checked by the controller (ValueError)
  options.setpoints = setpoints_argument(setpoints, joints);
  options.deadline = {deadline, inject_deadline_misses, seed};  // checked by the controller (ValueError)
  plugin::ClosedLoopOptions loop;
  loop.duration_s = duration;
  // Standard deviations in deg and deg/s, as the program takes them; the sensors check them.
  loop.sensors = {noise_deg * M_PI / 180.0, noise_deg_per_s * M_PI / 180.0, measurement_delay, seed};
  loop.actuation_delay_s = actuation_delay;  // checked by the loop (ValueError)
  loop.integrator = plugin::integrator_from_name(integrator);  // std::invalid_argument (ValueError) naming the choices
  // The program's defaults (arm_receding_horizon): 1e-5 for the muscle Rosenbrock method, else 1e-8.
  loop.accuracy = !accuracy.is_none()                                            ? py::cast<double>(accuracy)
                  : loop.integrator == plugin::IntegratorKind::MuscleRosenbrock ? 1e-5
                                                                                 : 1e-8;
  if (!(loop.accuracy > 0.0 && loop.accuracy <= 1e-3)) throw py::value_error("accuracy: must lie in (0, 1e-3]");
  // The plant starts from its own state (its muscles' rest, or their equilibrium at a0).
  if (!plant.is_none() && !py::isinstance<Model>(plant)) throw py::value_error("plant: expected a flatsos.Model");
  const Model& given_plant = plant.is_none() ? m : plant.cast<const Model&>();
  const std::shared_ptr<const plugin::MusculoskeletalModel> pushed =
      disturbance.is_none() ? nullptr : with_disturbance(*given_plant.model, disturbance);
  const plugin::MusculoskeletalModel& simulated = pushed ? *pushed : *given_plant.model;
  const std::shared_ptr<const plugin::MusculoskeletalModel> plant_model =
      pushed ? pushed : plant.is_none() ? nullptr : given_plant.model;

  py::dict out;
  planner::RecedingHorizonRun run;
  std::unique_ptr<planner::RecedingHorizonController> kept;
  std::vector<std::string> warnings;
  int plan_failures = 0, steps = 0, clamped = 0, bounded = 0;
  {
    py::gil_scoped_release release;
    // Bad options: std::invalid_argument naming the field (a ValueError).
    const auto flat = flat_for_task(m, {q0_rad, target_rad});
    kept = std::make_unique<planner::RecedingHorizonController>(*flat, options, plant_model);
    planner::RecedingHorizonController& controller = *kept;
    auto plant_flat = plant.is_none() ? flat : flat_for_task(given_plant, {q0_rad, target_rad});
    if (pushed) plant_flat = std::make_shared<const planner::FlatOutputMap>(plant_flat->withModel(pushed));
    const SimTK::State initial = planner::start_state(*plant_flat, q0_rad, qd0_rad_per_s, activations, reserves_N);
    run = planner::run_receding_horizon(controller, initial, loop, settle_tolerance);
    warnings = controller.warnings();
    plan_failures = controller.planFailures();
    steps = controller.steps();
    clamped = controller.clampedSamples();
    bounded = controller.boundedSteps();
  }
  std::string message;
  for (const auto& f : run.failures) message += (message.empty() ? "" : "; ") + f;
  out["time"] = column_vector(run.loop.states, "time");
  out["q"] = columns_table(run.loop.states, joint_value_columns(simulated));
  out["activation"] = columns_table(run.loop.states, muscle_columns(simulated, "/activation"));
  out["excitation"] = columns_table(run.loop.controls, muscle_columns(simulated, ""));
  out["settling_time"] = run.settling_time_s >= 0.0 ? py::object(py::float_(run.settling_time_s)) : py::object(py::none());
  out["real_time_factor"] = run.loop.real_time_factor;
  out["wall_seconds"] = run.loop.wall_seconds;
  out["success"] = run.success();
  out["message"] = message;
  out["finite"] = run.loop.finite;
  out["steps"] = steps;
  out["plan_failures"] = plan_failures;
  out["clamped_samples"] = clamped;
  out["bounded_steps"] = bounded;
  out["integrator_steps"] = run.loop.integrator_steps;
  out["warnings"] = warnings;
  add_real_time_report(out, *kept, run);
  return out;
}

}  // namespace

void register_receding_horizon(py::module_& m) {
  m.def("run_receding_horizon", &run_receding_horizon, py::arg("model"), py::arg("q0"), py::arg("target"),
        py::arg("duration"), py::kw_only(), py::arg("qd0") = py::none(), py::arg("a0") = py::none(),
        py::arg("reserves") = 1.0, py::arg("horizon") = 0.5, py::arg("grid_points") = 11, py::arg("period") = 0.05,
        py::arg("solver") = "exact", py::arg("bounds") = true, py::arg("observer_gain") = 40.0,
        py::arg("quick_arrival") = 0.5, py::arg("integrator") = "rosenbrock", py::arg("accuracy") = py::none(), py::arg("plant") = py::none(),
        py::arg("settle_tolerance") = M_PI / 180.0, py::arg("disturbance") = py::none(), py::arg("noise_deg") = 0.0,
        py::arg("noise_deg_per_s") = 0.0, py::arg("seed") = 1u, py::arg("measurement_delay") = 0.0,
        py::arg("actuation_delay") = 0.0, py::arg("deadline") = 0.0, py::arg("inject_deadline_misses") = 0.0, py::arg("setpoints") = py::none(),
        "The receding-horizon controller moving the model from rest at q0 (rad) to `target` (rad) on a Simbody "
        "plant for `duration` s: every `period` s a plan over `horizon` s (a cubic to the target, the torque box "
        "on `grid_points` postures, the SLP by `solver`: 'exact', 'simplex' or 'ipopt'), its excitations kept "
        "in [0, 1] when `bounds`.\n"
        "Start: qd0 (rad/s, default 0) with activations a0 and tendons in static equilibrium, or (a0=None) the "
        "minimum-effort rest state for `reserves` (minimum tendon force, N, one number or one per muscle). "
        "observer_gain: the disturbance observer, 1/s (default 40: removes the offset of a "
        "model mismatch or a push; 0: the paper's controller). quick_arrival: below 1 (default 0.5), the "
        "fraction of the horizon a plan first tries to come to rest at the target in while the observer finds "
        "the model explaining the motion, the whole horizon where that fails (errors near the target corrected "
        "faster; 1: always the whole horizon, the paper's). plant: another flatsos.Model with the same joints and muscles to simulate instead of "
        "`model` (model mismatch). disturbance: rows (time_s, forces per joint: N m, N along a slider) pushing "
        "the plant's joints, each held until the next row's time. noise_deg, noise_deg_per_s: standard "
        "deviations of the measured pins' angles and speeds (seed: of the noise and of injected misses); "
        "measurement_delay: s between a measurement and the control time it is used at; actuation_delay: s "
        "between a control time and its excitations reaching the muscles. deadline: s a plan may "
        "take; a later one is not used (the previous plan's tail runs; 0: none); inject_deadline_misses: for "
        "tests, this fraction of the steps miss it at random. setpoints: (time_s, target_rad) rows, each the "
        "target from its time on. integrator: 'rosenbrock' (default accuracy 1e-5), 'bdf' or 'rkm' (1e-8).\n"
        "Returns a dict: 'time' (s), 'q' (rad, one row per report), 'activation' and 'excitation' (one column "
        "per muscle; the excitation in effect), 'settling_time' (s from which every joint stays within "
        "settle_tolerance rad of the target; None: never), 'real_time_factor', 'success' (settled, finite, every "
        "plan solved) and 'message' (why not), 'steps', 'plan_failures', 'clamped_samples', 'bounded_steps', "
        "'integrator_steps', 'warnings', 'deadline_misses', 'longest_deadline_miss_run', 'worst_step_seconds', "
        "'fallbacks' (steps run on the previous plan's tail), 'faults' (counts by kind) and 'setpoint_settling' "
        "(with setpoints: per target, s after it took effect until settled; None: never). Releases the GIL while "
        "it runs.");
}

}  // namespace flatsos::python
