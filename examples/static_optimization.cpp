// static_optimization: OpenSim's static optimization along a measured motion
// (planner/static_optimization.hpp): per frame, the activations of least sum a^p whose muscle
// forces produce the motion's inverse-dynamics torques. Writes OUT/<model>_StaticOptimization_
// activation.sto and _force.sto as OpenSim names them, and OUT/summary.json.
#include <CLI/CLI.hpp>

#include <filesystem>
#include <iostream>

#include "example_support.hpp"
#include "flatsos/planner/static_optimization.hpp"
#include "flatsos/plugin/io/sto_file.hpp"
#include "programs.hpp"

namespace flatsos::programs::static_optimization {

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
namespace ex = flatsos::examples;

int run(int argc, char** argv) {
  CLI::App app{"Static optimization along a measured motion, as OpenSim's StaticOptimization tool solves it.\n"
               "The motion (an OpenSim coordinates table: .mot or .sto, degrees or radians as its header says) is "
               "filtered and splined as OpenSim's tools do; at each frame the activations a in [0, 1] of least "
               "sum w a^p make the muscles produce the inverse-dynamics joint torques. An .osim model uses its "
               "GeometryPaths (wrapping included) unless --paths fitted.\n"
               "Writes OUT/<model>_StaticOptimization_activation.sto, OUT/<model>_StaticOptimization_force.sto and "
               "OUT/summary.json; exits 1 when a frame cannot be balanced (the reason in the summary)."};
  std::string model_path, motion_path, out_dir = "results/static_optimization", rule_name;
  double cutoff_hz = 6.0;
  fpl::StaticOptimizationOptions options;
  ex::OpenSimModelOptions osim;
  osim.paths = "";  // the default depends on the model file
  app.add_option("--model", model_path, "model file (JSON), or an OpenSim model (.osim) imported on the way")->required();
  app.add_option("--coordinates", motion_path, "measured motion: coordinates table (.mot or .sto)")->required()->check(CLI::ExistingFile);
  app.add_option("--paths", osim.paths, "muscle paths: geometry (an .osim's GeometryPaths, the default for .osim) or fitted (the polynomials)")
      ->check(CLI::IsMember({"fitted", "geometry"}));
  CLI::Option* opensim_2 =
      app.add_flag("--opensim-2-muscles", osim.opensim_2_muscles,
                   "an .osim's Thelen2003Muscles as OpenSim 2.x modelled them, and OpenSim 2.x's force per activation "
                   "(to reproduce results of that time)");
  ex::add_degroote_options(app, osim, opensim_2);
  app.add_option("--cutoff-hz", cutoff_hz, "low-pass cutoff of the coordinates, Hz (OpenSim's; negative: no filtering)")
      ->capture_default_str();
  app.add_option("--activation-exponent", options.activation_exponent, "p in sum w a^p (OpenSim's activation_exponent)")
      ->capture_default_str()->check(CLI::Range(1.000001, 100.0));
  app.add_option("--reserve-optimal-torque-N-m", options.reserve_optimal_torque_N_m,
                 "one reserve actuator per joint with this optimal torque (N m; N on a slider); 0: none")
      ->capture_default_str()->check(flatsos::examples::nonnegative_number());
  app.add_option("--strength-rule", rule_name,
                 "a muscle's force per unit activation: opensim2 (isometric with its elastic tendon, passive force "
                 "included, times a generic force-velocity factor) or rigid-tendon (OpenSim 4's); default: opensim2 "
                 "with --opensim-2-muscles, else rigid-tendon")
      ->check(CLI::IsMember({"opensim2", "rigid-tendon"}));
  app.add_option("--out", out_dir, "output folder")->capture_default_str();
  if (const int rc = ex::parse_arguments(app, argc, argv); rc >= 0) return rc;
  try {
    const bool is_osim = std::filesystem::path(model_path).extension() == ".osim";
    if (osim.paths.empty()) osim.paths = is_osim ? "geometry" : "fitted";
    const auto model = ex::load_model(model_path, "static_optimization", osim);
    if (!rule_name.empty())
      options.strength_rule = rule_name == "opensim2" ? fpl::MuscleStrengthRule::OpenSim2 : fpl::MuscleStrengthRule::RigidTendon;
    const fp::ProcessedCoordinates motion = fpl::read_motion_for(*model, motion_path, cutoff_hz);
    const fpl::StaticOptimizationResult r = fpl::static_optimization(*model, motion, options);
    std::filesystem::create_directories(out_dir);
    const std::string stem = out_dir + "/" + model->description().name + "_StaticOptimization_";
    fp::write_sto(stem + "activation.sto", fpl::static_optimization_activation_table(*model, r));
    fp::write_sto(stem + "force.sto", fpl::static_optimization_force_table(*model, r));
    nlohmann::json summary = {
        {"model", model_path},
        {"coordinates", motion_path},
        {"frames", r.time_s.size()},
        {"activation_exponent", options.activation_exponent},
        {"strength_rule", r.strength_rule == fpl::MuscleStrengthRule::OpenSim2 ? "opensim2" : "rigid-tendon"},
        {"paths", osim.paths},
        {"reserve_optimal_torque_N_m", options.reserve_optimal_torque_N_m},
        {"largest_reserve_torque_N_m", r.reserve_torque_N_m.size() ? r.reserve_torque_N_m.cwiseAbs().maxCoeff() : 0.0},
        {"effort_sum_over_frames", r.effort.sum()},
        {"wall_seconds", r.wall_seconds},
        {"failures", r.failures},
        {"success", r.success()}};
    ex::write_json(out_dir + "/summary.json", summary);
    std::cout << "static_optimization: " << r.time_s.size() << " frames in " << 1e3 * r.wall_seconds << " ms, "
              << r.failures.size() << " failed; wrote " << stem << "{activation,force}.sto and summary.json\n";
    if (!r.success()) {
      std::cerr << "static_optimization: " << r.failures.front() << (r.failures.size() > 1 ? " (and more frames)" : "") << "\n";
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "static_optimization: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace flatsos::programs::static_optimization
