// arm_open_loop: an open-loop transfer of any model (default: the paper's scenario on the arm,
// from q = [0, 10] deg with the paper's activations to straight up in 3 s, the model file's
// scenario "open_loop"). Plans minimum-effort excitations, applies them open loop to the Simbody
// model from the same state, and writes the plan's and the simulation's states and controls
// (OUT/plan.sto, plan_controls.sto, simulation.sto, simulation_controls.sto) and OUT/summary.json.
#include <CLI/CLI.hpp>

#include <cmath>
#include <filesystem>
#include <optional>
#include <iostream>
#include <nlohmann/json.hpp>

#include "default_model.hpp"
#include "example_support.hpp"
#include "flatsos/planner/motion_planner.hpp"
#include "flatsos/planner/open_loop_study.hpp"
#include "flatsos/planner/planned_excitation.hpp"
#include "flatsos/planner/shortest_transfer.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"
#include "flatsos/plugin/model/static_equilibrium.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "scenario_inputs.hpp"
#include "programs.hpp"

namespace flatsos::programs::arm_open_loop {

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
namespace ex = flatsos::examples;

int run(int argc, char** argv) {
  CLI::App app{"Open-loop minimum-effort transfer of a muscle-driven model (default: the arm of Richter & Warner)\n"
               "planned by flatness and SOS optimization, then simulated open loop in Simbody.\n"
               "Writes OUT/plan.sto, OUT/simulation.sto (states), OUT/plan_controls.sto, OUT/simulation_controls.sto\n"
               "(excitations) as OpenSim storage (SI, radians), and OUT/summary.json."};
  std::string model_path = ex::default_model_path(), out_dir = "results/open_loop";
  ex::ScenarioOptions given;
  double accuracy = 1e-10;
  fpl::OpenLoopOptions options;
  fpl::OpenLoopStudyOptions study;
  CLI::Option_group* study_group =
      app.add_option_group("Study", "second opinions and tuning of the planner's stages (their defaults are the product's)");
  app.add_option("--model", model_path, "model file (JSON), or an OpenSim model (.osim) imported on the way")->capture_default_str();
  ex::OpenSimModelOptions osim_options;
  ex::add_opensim_model_options(app, osim_options);
  ex::add_scenario_options(app, given, "open_loop", true, 3.0, 10.0);
  app.add_option("--pieces", options.torque.pieces,
                 "torque-model pieces K (1 with --degree 0: the paper's box; 0: as many as the flat outputs' spans, "
                 "at least 12)")
      ->capture_default_str()->check(flatsos::examples::nonnegative_number());
  study_group->add_option("--degree", study.torque.degree, "torque-model polynomial degree r")->capture_default_str()->check(flatsos::examples::nonnegative_number());
  app.add_option("--flat-output-degree", options.sos.flat_output_degree,
                 "degree of the flat outputs' B-splines Y (4 with 1 span: the paper's quartic, --paper)")
      ->capture_default_str()->check(flatsos::examples::positive_number());
  app.add_option("--piece-growth", options.torque.piece_growth,
                 "each torque-model piece this many times as long as the one before (1: uniform; above 1: short "
                 "pieces at the start, where a fast motion's torques change)")
      ->capture_default_str()->check(flatsos::examples::positive_number());
  app.add_option("--flat-output-spans", options.sos.flat_output_spans,
                 "knot spans of the flat outputs' B-splines (0: chosen from the model's size, about 212 coefficients "
                 "over all flat outputs, at most 48 spans: 48 on the paper's arm)")
      ->capture_default_str()->check(flatsos::examples::nonnegative_number());
  app.add_option("--flat-output-span-growth", options.sos.flat_output_span_growth,
                 "each of the flat outputs' spans this many times as long as the one before (1: uniform; above 1: "
                 "short spans at the start, where a low-effort transfer spends its effort; 0: by the effort, 1 for "
                 "a linear one, 1.06 for a nonlinear one, then 1 where 1.06 finds no plan)")
      ->capture_default_str()->check(flatsos::examples::nonnegative_number());
  std::string effort_name = "paper";
  app.add_option("--effort", effort_name,
                 "what the plan minimizes: paper (the model's effort_weights times the tendon forces, the paper's "
                 "linear effort; tendon_force is the same) or the integral of squared or cubed excitations (OpenSim "
                 "Moco's default: excitation_squared), activations or stresses, along the prescribed path")
      ->capture_default_str()->check(CLI::IsMember(ex::effort_option_names()));
  int free_path_spans = 0;
  app.add_option("--free-path-spans", free_path_spans,
                 "optimize the joint path too: a degree-8 B-spline on this many spans through the same boundary "
                 "conditions (0: the prescribed degree-8 polynomial)")
      ->capture_default_str()->check(flatsos::examples::nonnegative_number());
  app.add_option("--free-path-span-growth", options.free_path.span_growth,
                 "each of the free path's spans this many times as long as the one before (1: uniform; above 1: "
                 "short spans at the start, where a low-effort transfer moves fast)")
      ->capture_default_str()->check(flatsos::examples::positive_number());
  study_group->add_option("--free-path-torque-refinements", study.free_path.max_torque_refinements,
                 "at most this many doublings of the torque pieces for the plan along the optimized path, while it "
                 "fails or costs more than 0.5 % above the path stage's cost at its points (0: none)")
      ->capture_default_str()->check(CLI::Range(0, 10));
  study_group->add_option("--free-path-start-min-spans", study.free_path.start_min_spans,
                 "the prescribed path's plan, which starts the free path's optimization, in the coarsest basis "
                 "nested in the flat outputs' with at least this many spans (0: the flat outputs' own)")
      ->capture_default_str()->check(flatsos::examples::nonnegative_number());
  study_group->add_option("--free-path-exchange-tolerance", study.free_path.exchange_relative_tolerance,
                 "joint_newton: the path's exchange ends once a round changes the cost at its points by at most this "
                 "fraction of it (0: only when the check grid holds)")
      ->capture_default_str()->check(flatsos::examples::nonnegative_number());
  std::string free_path_method = fpl::to_string(study.free_path.method);
  study_group->add_option("--free-path-method", free_path_method,
                 "how the free joint path moves: reduced_quasi_newton (BFGS on the bounded plan's cost as a "
                 "function of the path; fastest on few spans) or joint_newton (one Ipopt problem over the plan and "
                 "the path; converges on 24-48 spans too)")
      ->capture_default_str()
      ->check(CLI::IsMember({fpl::to_string(fpl::FreePathMethod::ReducedQuasiNewton),
                             fpl::to_string(fpl::FreePathMethod::JointNewton)}));
  bool paper = false;
  app.add_flag("--paper", paper,
               "Richter & Warner's configuration (one quartic flat-output polynomial, 12 cubic torque pieces) "
               "instead of the default quintic B-splines on spans chosen from the model; --pieces, --flat-output-degree and "
               "--flat-output-spans given as well override it");
  bool no_bounds = false;
  app.add_flag("--no-bounds", no_bounds,
               "plan with the reserves only: excitations outside [0, 1] or activations above 1 then make the plan "
               "infeasible instead of being constrained");
  std::string sos_method = fpl::to_string(study.sos.method);
  study_group->add_option("--sos-method", sos_method,
                 "how the reserves' program is solved: exchange (an exchange of LPs, then certificates of the "
                 "near-active pieces) or whole_program_nlp (one Ipopt problem with a certificate of every piece, "
                 "the reference formulation; it checks the excitation bounds instead of imposing them)")
      ->capture_default_str()
      ->check(CLI::IsMember({fpl::to_string(fpl::SosProgramMethod::Exchange),
                             fpl::to_string(fpl::SosProgramMethod::WholeProgramNlp)}));
  bool shortest_time = false;
  fpl::ShortestTransferOptions shortest;
  app.add_flag("--shortest-time", shortest_time,
               "plan the shortest transfer instead: the least duration with a plan, searched down from --duration-s "
               "(which must have one) in steps of --shortest-time-ratio, then by bisection; simulates that plan");
  app.add_option("--shortest-time-lower-s", shortest.lower_s, "the shortest duration the search tries, s")
      ->capture_default_str()->check(flatsos::examples::positive_number());
  app.add_option("--shortest-time-ratio", shortest.scan_ratio, "each scanned duration is this fraction of the one before")
      ->capture_default_str()->check(CLI::Range(0.01, 0.99));
  app.add_option("--shortest-time-tolerance-s", shortest.tolerance_s, "the bisection's resolution, s")
      ->capture_default_str()->check(flatsos::examples::positive_number());
  app.add_option("--accuracy", accuracy, "integrator accuracy")->capture_default_str()->check(CLI::Range(1e-14, 1e-3));
  long max_steps = ex::kDefaultMaxIntegratorSteps;
  ex::add_max_steps_option(app, max_steps);
  std::string integrator = "auto";
  ex::add_integrator_option(app, integrator,
                            "integrator of the open-loop simulation: rkm (Runge-Kutta-Merson), bdf (CPodes), "
                            "rosenbrock (implicit in the muscles) or auto (rkm, bdf where the muscles are stiff at "
                            "the start)");
  app.add_option("--out", out_dir, "output folder")->capture_default_str();
  if (const int rc = ex::parse_arguments(app, argc, argv); rc >= 0) return rc;

  try {
    const auto model = ex::load_model(model_path, "arm_open_loop", osim_options);
    const int m = model->numMuscles();
    const ex::ScenarioInputs in = ex::resolve_scenario(*model, "open_loop", given, 3.0, 10.0);
    const fpl::FlatOutputMap flat = ex::task_flat_outputs(model, in, "arm_open_loop");
    if (paper) {  // the preset's basis, except where the command line names one
      const fpl::OpenLoopOptions preset = fpl::open_loop_options(fpl::Preset::Paper);
      if (app.count("--pieces") == 0) options.torque.pieces = preset.torque.pieces;
      if (app.count("--flat-output-degree") == 0) options.sos.flat_output_degree = preset.sos.flat_output_degree;
      if (app.count("--flat-output-spans") == 0) options.sos.flat_output_spans = preset.sos.flat_output_spans;
    }
    options.sos.bounds.enforce = !no_bounds;
    study.sos.method = fpl::sos_program_method(sos_method);
    options.free_path.enabled = free_path_spans > 0;
    if (free_path_spans > 0) options.free_path.spans = free_path_spans;
    study.free_path.method = fpl::free_path_method(free_path_method);
    options.duration_s = in.duration_s;
    options.target_q_rad = in.target_q_rad;
    options.reserves_N = in.reserves_N;
    options.effort = ex::effort_option(effort_name);
    study.torque.samples_per_piece = std::max(study.torque.samples_per_piece, options.torque.pieces == 1 ? 31 : 0);

    SimTK::State s = ex::initial_state(flat, in);
    const fpl::MuscleState s0 = fpl::muscle_state_of(*model, s);

    std::optional<fpl::ShortestTransfer> search;
    if (shortest_time) {
      shortest.upper_s = in.duration_s;
      fp::ModelWorkspace workspace = flat.makeWorkspace();
      search = fpl::shortest_transfer(flat, workspace, s0, options, shortest, study);
      std::cout << "arm_open_loop: shortest transfer " << fpl::to_string(search->status)
                << (search->status == fpl::SolveStatus::Solved ? ", " + ex::format(search->shortest_s) + " s" : "")
                << (search->message.empty() ? "" : ": " + search->message) << " (" << search->tried.size() << " plans, "
                << search->seconds << " s)\n";
    }
    const fpl::OpenLoopPlan plan = search ? search->plan : fpl::plan_open_loop(flat, s0, options, study);
    const double duration_s = search ? search->shortest_s : in.duration_s;
    std::filesystem::create_directories(out_dir);
    nlohmann::json summary = ex::plan_summary(plan, flat);
    if (search) summary["shortest_transfer"] = ex::shortest_transfer_summary(*search);
    summary["model_file"] = model_path;
    summary["problem"] = ex::problem_summary(flat);
    summary["inputs"] = in.describe();
    summary["preset"] = fpl::to_string(paper ? fpl::Preset::Paper : fpl::Preset::Best);
    summary["warnings"] = ex::print_warnings("arm_open_loop", model->warnings(), plan.warnings);
    std::cout << "arm_open_loop: plan " << fpl::to_string(plan.status) << (plan.message.empty() ? "" : ": " + plan.message)
              << "\n  " << (plan.sos.effort_name.empty() ? std::string("effort") : plan.sos.effort_name) << " "
              << plan.sos.effort_value << " " << plan.sos.effort_unit << ", " << plan.sos.ipopt_iterations << " Ipopt iterations in "
              << plan.sos.ipopt_calls << " calls"
              << (plan.sos.ipopt_linear_solver.empty() ? "" : " (KKT systems by " + plan.sos.ipopt_linear_solver + ")")
              << ", setup " << 1e3 * plan.setup_seconds << " ms, solve "
              << 1e3 * plan.solve_seconds << " ms, certificates " << plan.sos.certified_pieces << "/"
              << plan.sos.near_active_pieces << " (" << 1e3 * plan.certify_seconds << " ms)\n";
    if (plan.status != fpl::SolveStatus::Solved || (search && search->status != fpl::SolveStatus::Solved)) {
      ex::write_json(out_dir + "/summary.json", summary);
      std::cerr << "arm_open_loop: no plan, nothing simulated (summary.json says why)\n";
      return 1;
    }

    // Open loop: the planned n(t) drives the Simbody muscles from the same state.
    const auto excitation = fpl::PlannedExcitation::create(flat, plan.path, *plan.Y);
    for (int j = 0; j < m; ++j) model->muscle(j).setExcitationSignal(s, excitation->signal(j));
    fp::SimulationOptions so;
    so.duration_s = duration_s;
    so.accuracy = accuracy;
    so.integrator = fp::integrator_from_name(integrator);
    so.report_interval_s = duration_s / 300.0;
    so.max_steps = max_steps;
    const flatsos::Stopwatch sim_wall;
    const fp::SimulationResult sim = fp::simulate(*model, s, so);
    const double sim_seconds = sim_wall.seconds();

    const ex::PlanTables planned = ex::plan_tables(flat, plan, sim.states);
    const ex::Tracking err = ex::compare(*model, planned.states, sim.states);
    summary["simulation"] = {{"success", sim.completed()},
                             {"step_limit_reached", sim.step_limit_reached},
                             {"message", sim.message},
                             {"integrator", fp::integrator_name(sim.integrator)},
                             {"accuracy", accuracy},
                             {"integrator_steps", sim.integrator_steps},
                             {"wall_seconds", sim_seconds}};
    summary["max_abs_q_error_deg"] = err.max_q_error_rad / ex::kRadPerDeg;  // over the pins
    summary["max_abs_slider_error_m"] = err.max_slider_error_m;
    summary["max_abs_activation_error"] = err.max_activation_error;
    summary["max_abs_tendon_length_error_m"] = err.max_tendon_length_error_m;

    auto sim_table = sim.states;
    sim_table.name = "simulation";
    sim_table.metadata = {{"success", sim.completed() ? "true" : "false"}, {"integrator_accuracy", ex::format(accuracy)}};
    auto sim_controls = sim.controls;
    sim_controls.name = "simulation_controls";
    fp::write_sto(out_dir + "/plan.sto", planned.states);
    fp::write_sto(out_dir + "/plan_controls.sto", planned.controls);
    fp::write_sto(out_dir + "/simulation.sto", sim_table);
    fp::write_sto(out_dir + "/simulation_controls.sto", sim_controls);
    ex::write_json(out_dir + "/summary.json", summary);
    const double simulated_s = sim.final_state.getTime() - s.getTime();
    std::cout << "  simulated open loop " << simulated_s << (sim.completed() ? "" : " of " + ex::format(duration_s)) << " s in "
              << sim_seconds << " s (" << fp::integrator_name(sim.integrator) << "): max |q error| "
              << err.max_q_error_rad / ex::kRadPerDeg << " deg"
              << (err.max_slider_error_m > 0.0 ? ", " + ex::format(err.max_slider_error_m) + " m along sliders" : "")
              << ", max |a error| " << err.max_activation_error
              << ", max |L_S error| " << err.max_tendon_length_error_m << " m\n  wrote " << out_dir << "/{plan.sto, plan_controls.sto, simulation.sto, simulation_controls.sto, summary.json}\n";
    if (!sim.completed()) {
      std::cerr << "arm_open_loop: simulation failed: " << sim.message << "\n";
      return 1;
    }
    return 0;
  } catch (const CLI::ValidationError& e) {
    std::cerr << "arm_open_loop: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "arm_open_loop: error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace flatsos::programs::arm_open_loop
