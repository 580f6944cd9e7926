// arm_forward: forward simulation of a muscle-driven model (default: the arm of Richter &
// Warner) from a given state under an excitation schedule; writes OUT/states.sto and
// OUT/controls.sto.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <filesystem>
#include <iostream>

#include "default_model.hpp"
#include "flatsos/plugin/io/initial_states.hpp"
#include "example_support.hpp"
#include "flatsos/plugin/io/excitation_file.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"
#include "flatsos/plugin/model/plausibility.hpp"
#include "flatsos/plugin/model/static_equilibrium.hpp"
#include "programs.hpp"

namespace flatsos::programs::arm_forward {

namespace fp = flatsos::plugin;
namespace ex = flatsos::examples;

namespace {
// Sizes of the optional per-joint / per-muscle lists (empty: the default applies).
void require_count_if_given(const std::vector<double>& v, int n, const std::string& option) {
  if (!v.empty()) ex::require_count(v, n, option);
}
}  // namespace

int run(int argc, char** argv) {
  CLI::App app{"Forward simulation of a muscle-driven Simbody model with flatsos Hill muscles.\n"
               "The tendons' initial state is required: give --ls0-m (one tendon length per muscle) or\n"
               "--equilibrate-tendons (static equilibrium for a0 at q0).\n"
               "Writes OUT/states.sto (OpenSim storage: joint angles in rad, muscle states in SI) and\n"
               "OUT/controls.sto (the excitations applied)."};
  std::string model_path = ex::default_model_path(), excitation_path, out_dir = "results/arm_forward";
  std::vector<double> q0_deg, qd0_deg_per_s, a0, ls0;
  bool equilibrate = false;
  double duration = 1.0, accuracy = 1e-8, report_interval = 0.01;
  app.add_option("--model", model_path, "model file (JSON), or an OpenSim model (.osim) imported on the way")->capture_default_str();
  ex::OpenSimModelOptions osim_options;
  ex::add_opensim_model_options(app, osim_options);
  app.add_option("--q0-deg", q0_deg, "initial joint angles, deg (a slider's in m; default 0)")->delimiter(',');
  app.add_option("--qd0-deg-per-s", qd0_deg_per_s, "initial joint speeds, deg/s (a slider's in m/s; default 0)")->delimiter(',');
  app.add_option("--a0", a0, "initial activations (default 0.05 each)")->delimiter(',');
  auto* ls_opt = app.add_option("--ls0-m", ls0, "initial tendon lengths, m, one per muscle (required unless --equilibrate-tendons)")
                     ->delimiter(',');
  auto* equilibrate_opt = app.add_flag("--equilibrate-tendons", equilibrate,
                                       "start tendons at static equilibrium for a0 at q0 (required unless --ls0-m)")
                              ->excludes(ls_opt);
  std::string initial_states_path;
  app.add_option("--initial-states", initial_states_path,
                 "a states file (.sto, OpenSim 3 or 4 columns) whose first row is the initial state, as OpenSim's "
                 "forward tool takes it; what it lacks comes from the options above, a missing fibre length from "
                 "static equilibrium")
      ->excludes(ls_opt)
      ->excludes(equilibrate_opt);
  app.add_option("--excitations", excitation_path,
                 "excitations over time: a controls .sto (OpenSim/Moco: time, /forceset/<muscle>, ...) or a CSV "
                 "(time,<muscle>,...); linear interpolation, held after the last row; default: excitation = "
                 "initial activation");
  app.add_option("--duration-s", duration, "simulated time, s")->capture_default_str()->check(flatsos::examples::positive_number());
  app.add_option("--accuracy", accuracy, "integrator accuracy")->capture_default_str()->check(CLI::Range(1e-14, 1e-2));
  app.add_option("--report-interval-s", report_interval, "time between rows of states.sto, s")
      ->capture_default_str()->check(flatsos::examples::positive_number());
  long max_steps = ex::kDefaultMaxIntegratorSteps;
  ex::add_max_steps_option(app, max_steps);
  std::string integrator = "auto";
  ex::add_integrator_option(app, integrator,
                            "rkm (Runge-Kutta-Merson), bdf (CPodes), rosenbrock (implicit in the muscles; these two "
                            "for stiff runs at tiny activations) or auto (rkm, bdf where the muscles are stiff at the "
                            "start)");
  app.add_option("--out", out_dir, "output folder")->capture_default_str();

  if (const int rc = ex::parse_arguments(app, argc, argv); rc >= 0) return rc;

  try {
    const auto model = ex::load_model(model_path, "arm_forward", osim_options);
    const int n = model->numJoints(), m = model->numMuscles();
    try {
      require_count_if_given(q0_deg, n, "--q0-deg");
      require_count_if_given(qd0_deg_per_s, n, "--qd0-deg-per-s");
      require_count_if_given(a0, m, "--a0");
      require_count_if_given(ls0, m, "--ls0-m");
      if (ls0.empty() && !equilibrate && initial_states_path.empty())
        throw CLI::ValidationError("--ls0-m", "give initial tendon lengths, --equilibrate-tendons or --initial-states");
    } catch (const CLI::Error& e) {
      std::cerr << "arm_forward: " << e.what() << "\n" << app.help();
      return 2;
    }
    const fp::ModelDescription& description = model->description();
    const Eigen::VectorXd q0 = q0_deg.empty() ? Eigen::VectorXd::Zero(n) : ex::from_display(description, ex::to_vector(q0_deg));
    ex::print_warnings("arm_forward", model->warnings(),
                       fp::joint_angle_warnings(model->description(), q0, "initial joint angles"));
    SimTK::State s = model->defaultState();
    model->setJointAngles(s, q0);
    model->setJointSpeeds(s, qd0_deg_per_s.empty() ? Eigen::VectorXd::Zero(n) : ex::from_display(description, ex::to_vector(qd0_deg_per_s)));
    const Eigen::VectorXd a = a0.empty() ? Eigen::VectorXd::Constant(m, 0.05) : ex::to_vector(a0);
    if (!initial_states_path.empty()) {
      model->setActivations(s, a);
      for (const std::string& note : fp::set_initial_states(*model, s, fp::read_sto(initial_states_path), initial_states_path))
        std::cout << "arm_forward: initial states: " << note << "\n";
    } else if (equilibrate) {
      fp::equilibrate_tendons(*model, s, a);
    } else {
      model->setActivations(s, a);
      model->setTendonLengths(s, ex::to_vector(ls0));
    }
    if (excitation_path.empty()) {
      model->setExcitations(s, a);
    } else {
      std::vector<std::string> names;
      for (const auto& md : model->description().muscles) names.push_back(md.parameters.name);
      const auto signals = fp::read_excitation_file(excitation_path, names);
      for (int j = 0; j < m; ++j) model->muscle(j).setExcitationSignal(s, signals[j]);
    }

    fp::SimulationOptions options;
    options.duration_s = duration;
    options.accuracy = accuracy;
    options.integrator = fp::integrator_from_name(integrator);
    options.report_interval_s = report_interval;
    options.max_steps = max_steps;
    const auto result = fp::simulate(*model, s, options);

    std::filesystem::create_directories(out_dir);
    auto table = result.states;
    table.metadata = {{"model", model_path},
                      {"accuracy", ex::format(accuracy)},
                      {"integrator", fp::integrator_name(result.integrator)},
                      {"integrator_steps", std::to_string(result.integrator_steps)},
                      {"success", result.completed() ? "true" : "false"}};
    if (!result.completed()) table.metadata.emplace_back("status", result.message);
    const std::string out_file = (std::filesystem::path(out_dir) / "states.sto").string();
    fp::write_sto(out_file, table);
    fp::write_sto((std::filesystem::path(out_dir) / "controls.sto").string(), result.controls);

    const Eigen::VectorXd q = ex::to_display(description, model->jointAngles(result.final_state));
    std::cout << "arm_forward: " << description.name << ", " << duration << " s, "
              << result.integrator_steps << " integrator steps\n  final joint angles (deg"
              << (std::any_of(description.joints.begin(), description.joints.end(), [](const auto& j) { return j.isSlider(); })
                      ? "; sliders in m"
                      : "")
              << "):";
    for (int i = 0; i < n; ++i) std::cout << ' ' << description.joints[i].name << '=' << q[i];
    std::cout << "\n  wrote " << out_file << " and controls.sto\n";
    if (!result.completed()) {
      std::cerr << "arm_forward: simulation failed: " << result.message << "\n";
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "arm_forward: error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace flatsos::programs::arm_forward
