#include "free_path_effort_bench.hpp"

#include <exception>

#include "flatsos/planner/collocation.hpp"
#include "flatsos/planner/effort.hpp"
#include "timing.hpp"

namespace flatsos::bench {

namespace fpl = flatsos::planner;
using nlohmann::json;

json free_path_squared_excitations(const fpl::FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                   const fpl::MuscleState& initial, const fpl::OpenLoopOptions& transfer) {
  fpl::OpenLoopOptions o = fpl::open_loop_options(fpl::Preset::Best);
  o.duration_s = transfer.duration_s;
  o.target_q_rad = transfer.target_q_rad;
  o.reserves_N = transfer.reserves_N;
  o.effort = fpl::effort_named("excitation_squared");
  json row = {{"duration_s", o.duration_s}};
  try {
    fpl::OpenLoopPlan prescribed, plan;
    const std::vector<double> along = repeat(1, [&] { prescribed = fpl::plan_open_loop(flat, workspace, initial, o); });
    o.free_path.enabled = true;
    o.free_path.spans = 12;
    o.free_path.span_growth = 1.2;
    const std::vector<double> t = repeat(1, [&] { plan = fpl::plan_open_loop(flat, workspace, initial, o); });
    row["prescribed_path"] = {{"status", fpl::to_string(prescribed.status)}, {"total", stats(along, 1e3, "ms")}};
    if (prescribed.status == fpl::SolveStatus::Solved) row["prescribed_path"]["effort_value"] = prescribed.sos.effort_value;
    row["flatness"] = {{"status", fpl::to_string(plan.status)},
                       {"message", plan.message},
                       {"total", stats(t, 1e3, "ms")},
                       {"path_stage_and_final_plan", {{"value", 1e3 * plan.free_path.seconds}, {"unit", "ms"}}},
                       {"path_quasi_newton_steps", plan.free_path.path_iterations},
                       {"path_value_evaluations", plan.free_path.evaluations},
                       {"path_exchange_rounds", plan.free_path.rounds},
                       {"path_points", plan.free_path.points},
                       {"path_effort_qp_steps", plan.free_path.sequential_lp_iterations}};
    if (plan.status == fpl::SolveStatus::Solved) row["flatness"]["effort_value"] = plan.sos.effort_value;
    // Intervals growing from t = 0, where the excitations change within milliseconds: converged
    // to 0.13 % (a uniform 200-interval mesh is 0.8 % below its limit).
    fpl::CollocationOptions mesh;
    mesh.mesh_intervals = 200;
    mesh.mesh_interval_growth = 1.02;
    mesh.effort = o.effort;
    fpl::CollocationResult reference;
    const std::vector<double> c = repeat(
        1, [&] { reference = fpl::solve_collocation_free_path(flat, workspace, prescribed.path, initial, o.reserves_N, mesh); });
    row["collocation"] = {{"status", fpl::to_string(reference.status)},
                          {"mesh_intervals", mesh.mesh_intervals},
                          {"mesh_interval_growth", mesh.mesh_interval_growth},
                          {"ipopt_iterations", reference.iterations},
                          {"total", stats(c, 1e3, "ms")}};
    if (reference.status == fpl::SolveStatus::Solved) {
      row["collocation"]["effort_value"] = reference.cost;
      if (plan.status == fpl::SolveStatus::Solved)
        row["flatness_effort_above_collocation_percent"] = 100.0 * (plan.sos.effort_value / reference.cost - 1.0);
    }
    row["collocation_time_over_flatness_time"] = c.front() / t.front();
  } catch (const std::exception& e) {
    // A model the free path or the reference does not cover (posture-dependent moment arms): why.
    row["skipped"] = e.what();
  }
  return row;
}

}  // namespace flatsos::bench
