// arm_receding_horizon: closed-loop control of any model (default: the paper's scenario on the
// arm, the model file's scenario "receding_horizon"). The model rests at q0 with its muscles in
// the minimum-effort static equilibrium; a receding-horizon controller (horizon 0.5 s, 11-point
// grid, replanned every 0.05 s by the SLP) moves it to the target ([20, 20] -> [80, 80] deg).
// Writes OUT/simulation.sto and OUT/simulation_controls.sto (row by row: a run of any length
// keeps no table), OUT/predictions/step_NNNN.sto (the predicted joint path of every step, unless
// --no-predictions) and OUT/summary.json. SIGTERM or SIGINT ends the run at the next control
// step with complete files of what it simulated and a summary that says it was interrupted.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "default_model.hpp"
#include "example_support.hpp"
#include "scenario_inputs.hpp"
#include "flatsos/planner/receding_horizon_controller.hpp"
#include "flatsos/planner/receding_horizon_study.hpp"
#include "flatsos/plugin/io/disturbance_file.hpp"
#include "flatsos/plugin/io/setpoint_file.hpp"
#include "flatsos/plugin/io/sto_stream.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/model/plausibility.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"
#include "programs.hpp"

namespace flatsos::programs::arm_receding_horizon {

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
namespace ex = flatsos::examples;

namespace {

// A stop asked for by SIGTERM or SIGINT (lock-free atomics may be set in a signal handler).
std::atomic<bool> stop_requested{false};
std::atomic<int> stop_signal{0};
extern "C" void request_stop(int signal_number) {
  stop_signal.store(signal_number);
  stop_requested.store(true);
}

// The run's rows straight to OUT/simulation.sto and OUT/simulation_controls.sto.
struct RowStreams {
  RowStreams(const fp::MusculoskeletalModel& model, const std::string& out_dir)
      : plant(model),
        states(out_dir + "/simulation.sto", fp::make_state_table(model, "simulation")),
        controls(out_dir + "/simulation_controls.sto", fp::make_controls_table(model, "simulation_controls")),
        row(fp::make_state_table(model)),
        control_row(fp::make_controls_table(model)) {}
  void report(const SimTK::State& state) {
    fp::append_state_row(plant, state, row);
    fp::append_controls_row(plant, state, control_row);
    states.append(row.rows.back());
    controls.append(control_row.rows.back());
    row.rows.clear();
    control_row.rows.clear();
  }
  const fp::MusculoskeletalModel& plant;
  fp::StoStream states, controls;
  fp::StoTable row, control_row;  // one row at a time
};

}  // namespace

int run(int argc, char** argv) {
  CLI::App app{"Receding-horizon control of a muscle-driven model (default: the arm of Richter & Warner):\n"
               "flatness-based SLP planning every control period, Simbody plant.\n"
               "Writes OUT/simulation.sto (states), OUT/simulation_controls.sto (excitations), OUT/predictions/\n"
               "step_NNNN.sto (each step's predicted joint path) and OUT/summary.json."};
  std::string model_path = ex::default_model_path(), out_dir = "results/receding_horizon", solver = "exact";
  ex::ScenarioOptions given;
  double accuracy = 0.0;  // 0: the integrator's default below
  fpl::RecedingHorizonControllerOptions options;
  app.add_option("--model", model_path, "model file (JSON), or an OpenSim model (.osim) imported on the way")->capture_default_str();
  ex::OpenSimModelOptions osim_options;
  ex::add_opensim_model_options(app, osim_options);
  ex::add_scenario_options(app, given, "receding_horizon", false, 2.0, 1.0);
  app.add_option("--horizon-s", options.plan.horizon_s, "planning horizon, s")->capture_default_str()->check(flatsos::examples::positive_number());
  app.add_option("--grid-points", options.plan.grid_points, "torque-box grid points over the horizon")
      ->capture_default_str()->check(CLI::Range(2, 10000));
  app.add_option("--period-s", options.control_period_s, "control period delta, s")->capture_default_str()->check(flatsos::examples::positive_number());
  app.add_option_group("Study", "second opinions (their defaults are the product's)")
      ->add_option("--slp-solver", solver,
                 "exact (vertex enumeration; the dual simplex where there are more than 20000 vertices), simplex "
                 "(Clp's dual simplex, restarted from the previous period's basis) or ipopt (the interior-point "
                 "reference); all tested against each other")
      ->capture_default_str()->check(CLI::IsMember({"exact", "simplex", "ipopt"}));
  bool no_bounds = false;
  app.add_flag("--no-excitation-bounds", no_bounds,
               "plan without the excitation bounds on each control period (the paper's step: excitations outside "
               "[0, 1] are clamped by the muscle and counted)");
  app.add_option("--observer-gain-per-s", options.disturbance_observer_gain_per_s,
                 "disturbance observer gain in [0, 1000] 1/s: the rate at which its estimate of the joint torque the "
                 "model's muscles miss (model mismatch, pushes) follows the measurement, so that neither leaves an "
                 "offset (0: the paper's controller, --paper)")
      ->capture_default_str()->check(CLI::Range(0.0, 1000.0));
  app.add_option("--quick-arrival", options.quick_arrival_fraction,
                 "below 1: the fraction of the horizon a step first plans to come to rest at the set point in, "
                 "while the observer finds the model explaining the motion; over the whole horizon where that plan "
                 "fails (errors near the target corrected faster; 1: always the whole horizon, the paper's)")
      ->capture_default_str()->check(CLI::Range(0.0, 1.0));
  bool paper = false;
  app.add_flag("--paper", paper,
               "Richter & Warner's controller: no disturbance observer (unless --observer-gain-per-s is given)");
  std::string plant_path;
  app.add_option("--plant", plant_path,
                 "model file (JSON) of the simulated plant, apart from the model the controller plans with (as "
                 "many joints and muscles; default: the model itself)");
  double plant_strength = 1.0;
  app.add_option("--plant-strength", plant_strength,
                 "every maximum isometric force of the plant times this factor (a plant weaker or stronger than the "
                 "model)")
      ->capture_default_str()->check(flatsos::examples::positive_number());
  std::string disturbance_path;
  app.add_option("--disturbance", disturbance_path,
                 "storage file (.sto) of external forces on the plant's joints: a time column and one column per "
                 "joint or coordinate (N m on a pin, N along a slider), each row held until the next")
      ->check(CLI::ExistingFile);
  std::string setpoint_path;
  app.add_option("--setpoints", setpoint_path,
                 "storage file (.sto) of set points: a time column and one column per joint or coordinate, each "
                 "row the target from its time on (degrees with inDegrees=yes in the header; the scenario's target "
                 "before the first row)")
      ->check(CLI::ExistingFile);
  fp::SensorOptions sensors;
  double noise_deg = 0.0, noise_deg_per_s = 0.0;
  app.add_option("--noise-deg", noise_deg, "standard deviation of the measured joint angles' noise, deg (pins; sliders are measured without noise)")
      ->capture_default_str()->check(flatsos::examples::nonnegative_number());
  app.add_option("--noise-deg-per-s", noise_deg_per_s,
                 "standard deviation of the measured joint speeds' noise, deg/s (pins)")
      ->capture_default_str()->check(flatsos::examples::nonnegative_number());
  app.add_option("--seed", sensors.seed, "seed of the measurement noise (and of injected deadline misses)")
      ->capture_default_str();
  app.add_option("--measurement-delay-s", sensors.delay_s,
                 "the joints measured at a control time were taken this long before it, s")
      ->capture_default_str()->check(flatsos::examples::nonnegative_number());
  double actuation_delay_s = 0.0;
  app.add_option("--actuation-delay-s", actuation_delay_s,
                 "the excitations a control step sets reach the muscles this long after it, s")
      ->capture_default_str()->check(flatsos::examples::nonnegative_number());
  app.add_option("--deadline-s", options.deadline.deadline_s,
                 "compute deadline of a control step's plan, s: a later plan is not used, the previous plan's tail "
                 "runs instead and the miss is counted (0: none)")
      ->capture_default_str()->check(flatsos::examples::nonnegative_number());
  app.get_option_group("Study")
      ->add_option("--inject-deadline-misses", options.deadline.injected_miss_fraction,
                   "for tests of the fallback: this fraction of the steps, at random, miss their deadline")
      ->capture_default_str()->check(CLI::Range(0.0, 1.0));
  // Defaults measured on this scenario against CPodes BDF at 1e-10 (docs/benchmarks.md): the
  // Rosenbrock method at 1e-5 stays within 8e-4 deg of it (RTF ~70); BDF and RKM at 1e-8.
  app.add_option("--accuracy", accuracy,
                 "integrator accuracy (default: 1e-5 for rosenbrock, 1e-8 for bdf and rkm)")
      ->check(CLI::Range(1e-14, 1e-3));
  // Planned activations go down to ~1e-3, where the tendon ODE is stiff: an explicit method
  // (rkm) needs ~4x the steps of an implicit one; see docs/benchmarks.md for the measurements.
  std::string integrator = "rosenbrock";
  ex::add_integrator_option(app, integrator,
                            "rosenbrock (implicit in the muscles, explicit in the multibody), bdf (CPodes) or rkm "
                            "(Runge-Kutta-Merson)");
  app.add_option("--out", out_dir, "output folder")->capture_default_str();
  bool write_predictions = true;
  app.add_flag("--predictions,!--no-predictions", write_predictions,
               "write each step's predicted joint path (OUT/predictions/); without, the controller keeps no "
               "history and memory stays flat however long the run")
      ->capture_default_str();
  if (const int rc = ex::parse_arguments(app, argc, argv); rc >= 0) return rc;

  try {
    const auto model = ex::load_model(model_path, "arm_receding_horizon", osim_options);
    const int n = model->numJoints();
    if (paper && app.count("--observer-gain-per-s") == 0) options.disturbance_observer_gain_per_s = 0.0;
    sensors.angle_noise_rad = noise_deg * ex::kRadPerDeg;
    sensors.speed_noise_rad_per_s = noise_deg_per_s * ex::kRadPerDeg;
    options.deadline.seed = sensors.seed;
    // The plant: another model file and/or other strengths; null when it is the model itself.
    std::shared_ptr<const fp::MusculoskeletalModel> plant;
    if (!plant_path.empty() || plant_strength != 1.0 || !disturbance_path.empty()) {
      fp::ModelDescription d = plant_path.empty() ? model->description() : fp::load_model_file(plant_path);
      for (auto& muscle : d.muscles) muscle.parameters.max_isometric_force_N *= plant_strength;
      auto disturbance = disturbance_path.empty() ? std::vector<fp::ExternalJointTorque>{}
                                                  : fp::read_disturbance_file(d, disturbance_path);
      plant = std::make_shared<const fp::MusculoskeletalModel>(std::move(d), std::move(disturbance));
    }
    const ex::ScenarioInputs in = ex::resolve_scenario(*model, "receding_horizon", given, 2.0, 1.0);
    const fpl::FlatOutputMap flat = ex::task_flat_outputs(model, in, "arm_receding_horizon");
    const double duration = in.duration_s;
    options.plan.target_q_rad = in.target_q_rad;
    options.plan.reserves_N = in.reserves_N;
    options.plan.solver = solver == "simplex" ? fpl::SlpSolver::Simplex : fpl::SlpSolver::VertexEnumeration;
    if (solver == "ipopt")  // the interior-point reference, through the controller's planner seam
      options.planner = [](const fpl::FlatOutputMap& f, fp::ModelWorkspace& w, const Eigen::VectorXd& q,
                           const Eigen::VectorXd& qd, const fpl::RecedingHorizonOptions& o, fpl::RecedingHorizonStep& out) {
        fpl::RecedingHorizonStudyOptions by_ipopt;
        by_ipopt.slp_by_ipopt = true;
        fpl::plan_receding_horizon_step(f, w, q, qd, o, by_ipopt, out);
      };
    options.plan.excitation_bounds.enforce = !no_bounds;
    options.keep_history = write_predictions;
    if (!setpoint_path.empty()) {
      const fp::SetpointRows rows = fp::read_setpoint_file(model->description(), setpoint_path);
      for (std::size_t k = 0; k < rows.times_s.size(); ++k) options.setpoints.push_back({rows.times_s[k], rows.targets_q_rad[k]});
    }
    if (options.control_period_s > options.plan.horizon_s)
      throw CLI::ValidationError("--period-s", "must not exceed --horizon-s");
    const fp::IntegratorKind kind = fp::integrator_from_name(integrator);
    if (accuracy == 0.0) accuracy = kind == fp::IntegratorKind::MuscleRosenbrock ? 1e-5 : 1e-8;

    // The paper's loop starts at rest (no initial speeds or activations to give): the plant's own.
    fpl::RecedingHorizonController controller(flat, options, plant);  // checks the plant's sizes first
    SimTK::State s = plant ? ex::initial_state(flat.withModel(plant), in) : ex::initial_state(flat, in);
    std::vector<std::string> found = fp::joint_angle_warnings(model->description(), in.q0_rad, "initial joint angles");
    for (auto& w : controller.warnings()) found.push_back(std::move(w));
    const std::vector<std::string> warnings = ex::print_warnings("arm_receding_horizon", model->warnings(), found);
    fp::ClosedLoopOptions loop_options;
    loop_options.duration_s = duration;
    loop_options.integrator = kind;
    loop_options.accuracy = accuracy;
    loop_options.sensors = sensors;
    loop_options.actuation_delay_s = actuation_delay_s;
    std::filesystem::create_directories(out_dir);
    RowStreams rows(controller.plant(), out_dir);
    loop_options.keep_tables = false;
    loop_options.report = [&rows](const SimTK::State& state) { rows.report(state); };
    loop_options.stop = &stop_requested;
    std::signal(SIGTERM, request_stop);
    std::signal(SIGINT, request_stop);
    const fpl::RecedingHorizonRun rh_run = fpl::run_receding_horizon(controller, s, loop_options, ex::kRadPerDeg);
    std::signal(SIGTERM, SIG_DFL);
    std::signal(SIGINT, SIG_DFL);
    const fp::ClosedLoopResult& run = rh_run.loop;
    std::vector<double> plan_times;
    for (const auto& rec : controller.history()) plan_times.push_back(rec.plan_seconds);
    const fpl::StepTimeHistogram& step_times = controller.stepTimes();
    const int steps = controller.steps();
    const bool finite = run.finite;
    const double settling = rh_run.settling_time_s;
    const Eigen::VectorXd target = options.plan.target_q_rad;
    const Eigen::VectorXd q_final = ex::to_display(model->description(), model->jointAngles(run.final_state));
    // The task: reach the target and stay within 1 deg of it, with every plan solved. A run that
    // fails it still writes its (complete) files, says why in the summary and exits 1.
    std::vector<std::string> failures = rh_run.failures;
    if (run.stopped)  // the run's own words name no signal
      failures.front() = std::string("interrupted by ") + (stop_signal.load() == SIGINT ? "SIGINT" : "SIGTERM") +
                         " at t = " + ex::format(run.final_state.getTime()) + " s of " + ex::format(duration) + " s";
    std::string message;
    for (const auto& f : failures) message += (message.empty() ? "" : "; ") + f;
    nlohmann::json summary;
    summary["success"] = rh_run.success();
    summary["message"] = message;
    summary["interrupted"] = run.stopped;
    summary["simulated_s"] = run.final_state.getTime() - s.getTime();
    summary["final_q_deg"] = std::vector<double>(q_final.data(), q_final.data() + n);
    summary["target_q_deg"] = std::vector<double>(n);
    const Eigen::VectorXd target_shown = ex::to_display(model->description(), target);  // a slider's in m
    for (int i = 0; i < n; ++i) summary["target_q_deg"][i] = target_shown[i];
    summary["model_file"] = model_path;
    summary["problem"] = ex::problem_summary(flat);
    summary["inputs"] = in.describe();
    summary["warnings"] = warnings;
    summary["settling_time_s"] = settling >= 0.0 ? nlohmann::json(settling) : nlohmann::json(nullptr);
    summary["steps"] = steps;
    if (!plan_times.empty())  // (kept with the history only)
      summary["plan_seconds"] = {{"median", ex::median(plan_times)}, {"max", *std::max_element(plan_times.begin(), plan_times.end())}};
    summary["control_step_seconds"] = {{"median", step_times.quantile(0.5)},  // to 1 %
                                       {"p99", step_times.quantile(0.99)},
                                       {"max", controller.worstStepSeconds()}};
    summary["wall_seconds"] = run.wall_seconds;
    summary["real_time_factor"] = run.real_time_factor;
    summary["excitation_clamps"] = controller.clampedSamples();
    summary["excitation_bounds"] = {{"enforced", !no_bounds}, {"bounded_steps", controller.boundedSteps()}};
    summary["plan_failures"] = controller.planFailures();
    summary["finite"] = finite;
    summary["integrator"] = integrator;
    summary["integrator_accuracy"] = accuracy;
    summary["integrator_steps"] = run.integrator_steps;
    summary["integrator_attempts"] = run.integrator_attempts;
    summary["slp_solver"] = solver;
    summary["observer_gain_per_s"] = options.disturbance_observer_gain_per_s;
    summary["quick_arrival_fraction"] = options.quick_arrival_fraction;
    summary["plant"] = {{"model_file", plant_path.empty() ? model_path : plant_path},
                        {"strength", plant_strength},
                        {"disturbance_file", disturbance_path}};
    const fpl::ControllerFaults& faults = controller.faults();
    summary["deadline_misses"] = faults.deadline_misses;
    summary["longest_deadline_miss_run"] = faults.longest_miss_run;
    summary["worst_step_seconds"] = controller.worstStepSeconds();
    summary["fallbacks"] = faults.fallbacks;
    summary["faults"] = nlohmann::json::object();
    for (const auto& [name, count] : fpl::named_fault_counts(faults, run.finite)) summary["faults"][name] = count;
    summary["sensors"] = {{"noise_deg", noise_deg},
                          {"noise_deg_per_s", noise_deg_per_s},
                          {"measurement_delay_s", sensors.delay_s},
                          {"actuation_delay_s", actuation_delay_s},
                          {"seed", sensors.seed}};
    summary["deadline"] = {{"deadline_s", options.deadline.deadline_s},
                           {"injected_miss_fraction", options.deadline.injected_miss_fraction}};
    summary["setpoint_settling_s"] = nlohmann::json::array();
    for (const double settled : rh_run.setpoint_settling_s)
      summary["setpoint_settling_s"].push_back(settled >= 0.0 ? nlohmann::json(settled) : nlohmann::json(nullptr));
    summary["setpoints_file"] = setpoint_path;
    summary["horizon_s"] = options.plan.horizon_s;
    summary["control_period_s"] = options.control_period_s;

    rows.states.header().metadata = {{"success", finite ? "true" : "false"},
                                     {"integrator_accuracy", ex::format(accuracy)},
                                     {"interrupted", run.stopped ? "true" : "false"}};
    rows.states.finish();
    rows.controls.finish();
    // One file per step (OpenSim tables need strictly increasing time); none left from a longer run.
    const std::filesystem::path predictions = std::filesystem::path(out_dir) / "predictions";
    std::filesystem::remove_all(predictions);
    if (write_predictions) std::filesystem::create_directories(predictions);
    for (const auto& table : rh_run.predictions) {
      char file[32];
      std::snprintf(file, sizeof file, "step_%04d.sto", std::stoi(table.metadataValue("step")));
      fp::write_sto((predictions / file).string(), table);
    }
    summary["prediction_files"] = rh_run.predictions.size();
    ex::write_json(out_dir + "/summary.json", summary);
    const auto& joints = model->description().joints;
    const bool any_slider = std::any_of(joints.begin(), joints.end(), [](const fp::JointDescription& j) { return j.isSlider(); });
    std::cout << "arm_receding_horizon: " << steps << " steps, final q = [" << q_final.transpose()
              << (any_slider ? "] (deg, a slider's m), settling " : "] deg, settling ")
              << (settling >= 0 ? ex::format(settling) + " s" : std::string("never")) << ", plan failures "
              << controller.planFailures() << ", clamped samples " << controller.clampedSamples() << ", bounded steps "
              << controller.boundedSteps() << "\n  median step "
              << 1e3 * step_times.quantile(0.5) << " ms, real-time factor " << run.real_time_factor << "\n  wrote " << out_dir
              << "/{simulation.sto, simulation_controls.sto, predictions/step_*.sto, summary.json}\n";
    if (!rh_run.success()) {
      std::cerr << "arm_receding_horizon: task failed: " << message << "\n";
      return run.stopped ? 128 + stop_signal.load() : 1;  // the shell's code for a run ended by a signal
    }
    return 0;
  } catch (const CLI::ValidationError& e) {
    std::cerr << "arm_receding_horizon: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "arm_receding_horizon: error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace flatsos::programs::arm_receding_horizon
