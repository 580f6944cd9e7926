#include "scaling.hpp"

#include <optional>
#include <stdexcept>
#include <vector>

#include "scenario_inputs.hpp"
#include "timing.hpp"
#include "flatsos/planner/receding_horizon_controller.hpp"
#include "flatsos/planner/rest_state.hpp"

namespace flatsos::bench {

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
namespace ex = flatsos::examples;
using nlohmann::json;

namespace {

// The targets by model size (muscles): RH step ms, open-loop plan ms, closed loop x real
// time. The paper's arm (6 muscles) keeps the targets it was given before.
struct Targets {
  double rh_step_ms, open_loop_ms, real_time_factor;
};
Targets targets_for(int muscles) {
  if (muscles <= 6) return {1.0, 20.0, 50.0};
  if (muscles <= 13) return {1.0, 50.0, 20.0};
  return {5.0, 500.0, 5.0};
}

json versus(double measured, double target, bool at_most) {
  return {{"measured", measured}, {"target", target}, {"met", at_most ? measured <= target : measured >= target}};
}

}  // namespace

json scaling_row(const std::string& model_path, int repetitions) {
  const auto model = fp::MusculoskeletalModel::fromFile(model_path);
  json row;
  row["model"] = model->description().name;
  row["joints"] = model->numJoints();
  row["muscles"] = model->numMuscles();
  row["constant_moment_arms"] = model->hasConstantMomentArms();

  // The flat-output map, once per model: the library's choice of E when the model gives none.
  std::optional<fpl::FlatOutputMap> made;
  const std::vector<double> map_s = repeat(1, [&] { made.emplace(model); });
  const fpl::FlatOutputMap& flat = *made;
  row["flat_outputs"] = flat.numFlatOutputs();
  row["flat_outputs_chosen_by_library"] = flat.flatOutputs().automatic;
  row["flat_output_map_ms"] = 1e3 * map_s.front();
  fp::ModelWorkspace ws = flat.makeWorkspace();

  // The open-loop plan of the model's scenario, default options (bounds where they bind).
  const ex::ScenarioInputs ol_in = ex::resolve_scenario(*model, "open_loop", {}, 3.0, 10.0);
  const fpl::MuscleState ms0 = fpl::muscle_state_of(*model, ex::initial_state(flat, ol_in));
  fpl::OpenLoopOptions ol = fpl::open_loop_options(fpl::Preset::Paper);
  ol.duration_s = ol_in.duration_s;
  ol.target_q_rad = ol_in.target_q_rad;
  ol.reserves_N = ol_in.reserves_N;
  std::vector<double> setup, solve, bounds, certify, check, total;
  fpl::OpenLoopPlan plan;
  for (int i = 0; i < repetitions; ++i) {
    plan = fpl::plan_open_loop(flat, ws, ms0, ol);
    setup.push_back(plan.setup_seconds);
    solve.push_back(plan.solve_seconds - plan.sos.bounds_seconds);
    bounds.push_back(plan.sos.bounds_seconds);
    certify.push_back(plan.certify_seconds);
    check.push_back(plan.check_seconds);
    total.push_back(plan.setup_seconds + plan.solve_seconds + plan.certify_seconds + plan.check_seconds);
  }
  if (plan.status != fpl::SolveStatus::Solved) throw std::runtime_error(row["model"].get<std::string>() + ": the open-loop scenario was not planned: " + plan.message);
  const Targets target = targets_for(model->numMuscles());
  row["open_loop_plan"] = {{"setup_ms", 1e3 * ex::median(setup)},
                           {"exchange_ms", 1e3 * ex::median(solve)},
                           {"excitation_bounds_ms", 1e3 * ex::median(bounds)},
                           {"certificates_ms", 1e3 * ex::median(certify)},
                           {"check_ms", 1e3 * ex::median(check)},
                           {"total", stats(total, 1e3, "ms")},
                           {"bounds_imposed", plan.sos.bounds_imposed},
                           {"cost_Ns", plan.sos.cost_N_s},
                           {"exchange_rounds", plan.sos.exchange_rounds},
                           {"certified_pieces", plan.sos.certified_pieces}};

  // The receding-horizon scenario: the closed loop (Rosenbrock at 1e-5, the program's default),
  // then its steps replanned from the states it passed through, for where a step's time goes.
  const ex::ScenarioInputs rh_in = ex::resolve_scenario(*model, "receding_horizon", {}, 2.0, 1.0);
  fpl::RecedingHorizonControllerOptions co;
  co.disturbance_observer_gain_per_s = 0.0;  // the paper's controller, as benchmarked before
  co.plan.target_q_rad = rh_in.target_q_rad;
  co.plan.reserves_N = rh_in.reserves_N;
  SimTK::State rest = model->defaultState();
  fpl::set_minimum_effort_rest_state(flat, rest, rh_in.q0_rad, rh_in.reserves_N);
  fp::ClosedLoopOptions loop;
  loop.duration_s = rh_in.duration_s;
  loop.integrator = fp::IntegratorKind::MuscleRosenbrock;
  loop.accuracy = 1e-5;
  std::vector<double> rtf, steps;
  fp::ClosedLoopResult last;
  int failures = 0, clamped = 0;
  for (int i = 0; i < repetitions; ++i) {
    fpl::RecedingHorizonController controller(flat, co);
    last = fpl::run_receding_horizon(controller, rest, loop).loop;
    rtf.push_back(last.real_time_factor);
    for (const auto& record : controller.history()) steps.push_back(record.wall_seconds);
    failures = controller.planFailures();
    clamped = controller.clampedSamples();
  }
  // Replanned in sequence into one step, as the controller does (its warm starts included).
  std::vector<double> grid, slp, period_bounds, whole;
  int bounded = 0;
  fpl::RecedingHorizonStep step;
  fpl::RecedingHorizonOptions plan_options = co.plan;
  plan_options.excitation_bounds.period_s = co.control_period_s;
  plan_options.excitation_bounds.samples = co.excitation_samples_per_period;
  const int n = model->numJoints();
  const std::size_t per_period = static_cast<std::size_t>(fp::ClosedLoopOptions{}.reports_per_period);
  for (std::size_t r = 0; r + 1 < last.states.rows.size(); r += per_period) {
    Eigen::VectorXd q(n), qd(n);
    for (int i = 0; i < n; ++i) {
      q[i] = last.states.rows[r][1 + 2 * static_cast<std::size_t>(i)];
      qd[i] = last.states.rows[r][2 + 2 * static_cast<std::size_t>(i)];
    }
    fpl::plan_receding_horizon_step(flat, ws, q, qd, plan_options, step);
    grid.push_back(step.grid_seconds);
    slp.push_back(step.slp.wall_seconds);
    period_bounds.push_back(step.bounds_seconds);
    whole.push_back(step.wall_seconds);
    bounded += step.bounds_imposed;
  }
  row["rh_step"] = {{"controller_step", stats(steps, 1e3, "ms (plan + excitations of the next period)")},
                    {"plan_ms", 1e3 * ex::median(whole)},
                    {"horizon_grid_ms", 1e3 * ex::median(grid)},
                    {"slp_ms", 1e3 * ex::median(slp)},
                    {"excitation_bounds_ms", 1e3 * ex::median(period_bounds)},
                    {"bounded_steps", bounded},
                    {"steps", whole.size()},
                    {"slp_rows", step.reserve_rows.rows()},
                    {"slp_pivots_last_step", step.slp.iterations}};  // 0: vertex enumeration
  row["closed_loop"] = {{"real_time_factor", stats(rtf, 1.0, "simulated s per wall s")},
                        {"integrator_steps", last.integrator_steps},
                        {"plan_failures", failures},
                        {"clamped_samples", clamped}};
  row["targets"] = {{"rh_step_ms", versus(1e3 * ex::median(steps), target.rh_step_ms, true)},
                    {"open_loop_plan_ms", versus(1e3 * ex::median(total), target.open_loop_ms, true)},
                    {"closed_loop_real_time_factor", versus(ex::median(rtf), target.real_time_factor, false)}};
  return row;
}

json growth(const json& rows) {
  json out = json::array();
  if (rows.empty()) return out;
  const json& base = rows.front();
  auto ratio = [](const json& a, const json& b) { return a.get<double>() / b.get<double>(); };
  for (const json& r : rows)
    out.push_back({{"model", r["model"]},
                   {"muscles", r["muscles"]},
                   {"flat_output_map", ratio(r["flat_output_map_ms"], base["flat_output_map_ms"])},
                   {"open_loop_plan", ratio(r["open_loop_plan"]["total"]["median"], base["open_loop_plan"]["total"]["median"])},
                   {"rh_step", ratio(r["rh_step"]["controller_step"]["median"], base["rh_step"]["controller_step"]["median"])},
                   {"closed_loop_wall_per_simulated_s",
                    ratio(base["closed_loop"]["real_time_factor"]["median"], r["closed_loop"]["real_time_factor"]["median"])}});
  return out;
}

}  // namespace flatsos::bench
