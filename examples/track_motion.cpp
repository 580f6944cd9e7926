// track_motion: the receding-horizon controller follows a measured motion (planner/tracking.hpp),
// as OpenSim's Computed Muscle Control does: each control period it plans the motion's next
// horizon from the measured state, starting where the muscles are, and applies the first
// period's excitations to the simulated plant. Writes OUT/<model>_states.sto,
// OUT/<model>_controls.sto, OUT/<model>_pErr.sto (CMC's names) and OUT/summary.json.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <filesystem>
#include <iostream>

#include "example_support.hpp"
#include "flatsos/planner/rest_state.hpp"
#include "flatsos/planner/static_optimization.hpp"
#include "flatsos/planner/task_region.hpp"
#include "flatsos/planner/tracking.hpp"
#include "flatsos/plugin/io/sto_file.hpp"
#include "flatsos/plugin/model/plausibility.hpp"
#include "programs.hpp"

namespace flatsos::programs::track_motion {

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
namespace ex = flatsos::examples;

namespace {

// The flat outputs over the postures the motion visits (the model's own ranges first).
fpl::FlatOutputMap motion_flat_outputs(std::shared_ptr<const fp::MusculoskeletalModel> model,
                                       const fp::ProcessedCoordinates& motion, const fpl::JointReference& reference) {
  fpl::FlatOutputMap flat = fpl::flat_outputs_for_task(model, fpl::reference_postures(reference, motion.report_times_s));
  if (!flat.flatOutputs().region.empty())
    std::cout << "track_motion: no flat outputs satisfy Assumption 1 over the joint ranges; chosen over the motion's region "
              << fp::describe_region(model->description(), flat.flatOutputs().region) << "\n";
  return flat;
}

std::vector<double> in_display_units(const fp::MusculoskeletalModel& model, const Eigen::VectorXd& per_joint) {
  const Eigen::VectorXd shown = ex::to_display(model.description(), per_joint);
  return std::vector<double>(shown.data(), shown.data() + shown.size());
}

}  // namespace

int run(int argc, char** argv) {
  CLI::App app{"Tracking a measured motion with the receding-horizon controller (what OpenSim's CMC does).\n"
               "The motion (an OpenSim coordinates table: .mot or .sto, degrees or radians as its header says) is "
               "filtered and splined as OpenSim's tools do. The plant starts on the motion at its first time with its "
               "muscles at the minimum-effort rest; every control period the controller plans the next horizon of the "
               "motion from the measured state and applies the first period's excitations.\n"
               "Writes OUT/<model>_states.sto, OUT/<model>_controls.sto, OUT/<model>_pErr.sto (reference - plant, "
               "rad or m) and OUT/summary.json; exits 1 when a plan fails or a coordinate leaves the motion by more "
               "than the tolerance (the files are complete and the summary says why)."};
  std::string model_path, motion_path, out_dir = "results/track_motion", effort_name = "excitation_squared";
  double cutoff_hz = 6.0, tolerance_deg = 1.0, plant_strength = 1.0, reserve_N = 1.0;
  fpl::RecedingHorizonControllerOptions options;
  ex::OpenSimModelOptions osim;
  app.add_option("--model", model_path, "model file (JSON), or an OpenSim model (.osim) imported on the way")->required();
  app.add_option("--coordinates", motion_path, "measured motion: coordinates table (.mot or .sto)")->required()->check(CLI::ExistingFile);
  ex::add_opensim_model_options(app, osim);
  app.add_option("--cutoff-hz", cutoff_hz, "low-pass cutoff of the coordinates, Hz (OpenSim's; negative: no filtering)")
      ->capture_default_str();
  app.add_option("--horizon-s", options.plan.horizon_s, "planning horizon, s")->capture_default_str()->check(flatsos::examples::positive_number());
  app.add_option("--period-s", options.control_period_s, "control period, s")->capture_default_str()->check(flatsos::examples::positive_number());
  app.add_option("--correction-s", options.plan.tracking_correction_s,
                 "time over which each plan removes the measured offset from the motion, s (at most the horizon; "
                 "default 0.06 with a squared or cubed effort, 0.075 with tendon_force)")
      ->check(flatsos::examples::positive_number());
  app.add_option("--observer-gain-per-s", options.disturbance_observer_gain_per_s,
                 "disturbance observer gain in [0, 1000] 1/s (0: none)")
      ->capture_default_str()->check(CLI::Range(0.0, 1000.0));
  app.add_option("--reserve-N", reserve_N, "the least tendon force every plan keeps in each muscle, N")
      ->capture_default_str()->check(flatsos::examples::nonnegative_number());
  app.add_option("--plant-strength", plant_strength,
                 "every maximum isometric force of the simulated plant times this factor (model mismatch)")
      ->capture_default_str()->check(flatsos::examples::positive_number());
  app.add_option("--tolerance-deg", tolerance_deg,
                 "the task fails where a coordinate leaves the motion by more than this, deg (a slider: mm)")
      ->capture_default_str()->check(flatsos::examples::positive_number());
  app.add_option("--effort", effort_name,
                 "what each plan minimizes over its horizon: the integral of the squared or cubed excitations (as CMC and "
                 "Moco), activations or stresses, or paper (the model's effort_weights: the paper's linear effort; "
                 "tendon_force is the same)")
      ->capture_default_str()->check(CLI::IsMember(ex::effort_option_names()));
  app.add_option("--out", out_dir, "output folder")->capture_default_str();
  if (const int rc = ex::parse_arguments(app, argc, argv); rc >= 0) return rc;
  try {
    if (options.control_period_s > options.plan.horizon_s) throw CLI::ValidationError("--period-s", "must not exceed --horizon-s");
    options.plan.effort = ex::effort_option(effort_name);
    if (!app.count("--correction-s"))
      options.plan.tracking_correction_s = std::min(fpl::tracking_correction_for(options.plan.effort.get()), options.plan.horizon_s);
    if (options.plan.tracking_correction_s > options.plan.horizon_s)
      throw CLI::ValidationError("--correction-s", "must not exceed --horizon-s");
    const auto model = ex::load_model(model_path, "track_motion", osim);
    const fp::ProcessedCoordinates motion = fpl::read_motion_for(*model, motion_path, cutoff_hz);
    auto reference = std::make_shared<const fpl::JointReference>(fpl::JointReference::fromMotion(*model, motion));
    const fpl::FlatOutputMap flat = motion_flat_outputs(model, motion, *reference);
    options.plan.reference = reference;
    options.plan.reserves_N = Eigen::VectorXd::Constant(model->numMuscles(), reserve_N);
    std::shared_ptr<const fp::MusculoskeletalModel> plant;
    if (plant_strength != 1.0) {
      fp::ModelDescription d = model->description();
      for (auto& muscle : d.muscles) muscle.parameters.max_isometric_force_N *= plant_strength;
      plant = std::make_shared<const fp::MusculoskeletalModel>(std::move(d));
    }
    fpl::RecedingHorizonController controller(flat, options, plant);
    const double t0 = reference->startTime_s();
    const SimTK::State s = fpl::tracking_start_state(plant ? flat.withModel(plant) : flat, *reference, options.plan.reserves_N);
    const double tolerance_rad = tolerance_deg * ex::kRadPerDeg;
    const fpl::TrackingRun run =
        fpl::run_tracking(controller, s, fpl::tracking_loop_options(), tolerance_rad, tolerance_deg * 1e-3);

    std::vector<double> step_seconds;
    nlohmann::json free_starts = nlohmann::json::array();  // periods whose plan could not start from the muscles
    for (const auto& rec : controller.history()) {
      step_seconds.push_back(rec.wall_seconds);
      if (!rec.free_start_message.empty()) free_starts.push_back({{"time_s", rec.time_s}, {"why", rec.free_start_message}});
    }
    std::string message;
    for (const auto& f : run.failures) message += (message.empty() ? "" : "; ") + f;
    std::filesystem::create_directories(out_dir);
    const std::string stem = out_dir + "/" + model->description().name + "_";
    fp::write_sto(stem + "states.sto", run.loop.states);
    fp::write_sto(stem + "controls.sto", run.loop.controls);
    fp::write_sto(stem + "pErr.sto", run.position_errors);
    const double duration = reference->endTime_s() - t0;
    nlohmann::json summary = {
        {"success", run.success()},
        {"message", message},
        {"model", model_path},
        {"coordinates", motion_path},
        {"problem", ex::problem_summary(flat)},
        {"start_time_s", t0},
        {"end_time_s", reference->endTime_s()},
        {"rms_error_deg", in_display_units(*model, run.rms_error)},
        {"max_abs_error_deg", in_display_units(*model, run.max_abs_error)},
        {"excitation_squared_integral", run.excitation_squared_integral},
        {"steps", controller.steps()},
        {"plan_failures", controller.planFailures()},
        {"excitation_clamps", controller.clampedSamples()},
        {"bounded_steps", controller.boundedSteps()},
        {"free_starts", free_starts},
        {"control_step_seconds", {{"median", ex::median(step_seconds)},
                                  {"max", *std::max_element(step_seconds.begin(), step_seconds.end())}}},
        {"controller_real_time_factor", options.control_period_s / ex::median(step_seconds)},
        {"real_time_factor", run.loop.real_time_factor},
        {"wall_seconds", run.loop.wall_seconds},
        {"horizon_s", options.plan.horizon_s},
        {"control_period_s", options.control_period_s},
        {"correction_s", options.plan.tracking_correction_s},
        {"observer_gain_per_s", options.disturbance_observer_gain_per_s},
        {"reserve_N", reserve_N},
        {"effort", effort_name},
        {"plant_strength", plant_strength},
        {"duration_s", duration}};
    ex::write_json(out_dir + "/summary.json", summary);
    const Eigen::VectorXd rms = ex::to_display(model->description(), run.rms_error);
    std::cout << "track_motion: " << controller.steps() << " steps over " << duration << " s, RMS error ["
              << rms.transpose() << "] deg, plan failures " << controller.planFailures() << ", median step "
              << 1e3 * ex::median(step_seconds) << " ms, real-time factor " << run.loop.real_time_factor << "\n  wrote "
              << stem << "{states,controls,pErr}.sto and summary.json\n";
    if (!run.success()) {
      std::cerr << "track_motion: task failed: " << message << "\n";
      return 1;
    }
    return 0;
  } catch (const CLI::ValidationError& e) {
    std::cerr << "track_motion: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "track_motion: error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace flatsos::programs::track_motion
