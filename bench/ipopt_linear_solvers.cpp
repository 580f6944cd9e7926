#include "ipopt_linear_solvers.hpp"

#include <random>
#include <string>
#include <vector>

#include "example_support.hpp"
#include "random_linear_program.hpp"
#include "timing.hpp"
#include "flatsos/planner/collocation.hpp"
#include "flatsos/planner/numerics/ipopt_linear_solver.hpp"
#include "flatsos/planner/numerics/linear_program.hpp"
#include "flatsos/planner/slp.hpp"
#include "flatsos/planner/slp_study.hpp"

namespace flatsos::bench {
namespace {

namespace fpl = planner;
using nlohmann::json;
using fpl::IpoptLinearSolver;

struct Timed {
  double median_s = 0.0;
  int iterations = 0;
  std::string status;
};

// f() returns (iterations, status); timed `reps` times under `solver`.
template <class F>
Timed timed_under(IpoptLinearSolver solver, int reps, F f) {
  fpl::set_ipopt_linear_solver(solver);
  Timed t;
  const std::vector<double> seconds = repeat(reps, [&] {
    const auto [iterations, status] = f();
    t.iterations = iterations;
    t.status = status;
  });
  fpl::set_ipopt_linear_solver(IpoptLinearSolver::Automatic);
  t.median_s = examples::median(seconds);
  return t;
}

json side_by_side(int kkt_dimension, const Timed& dense, const Timed& mumps) {
  auto per_iteration_ms = [](const Timed& t) { return t.iterations > 0 ? 1e3 * t.median_s / t.iterations : 0.0; };
  return {{"kkt_dimension", kkt_dimension},
          {"dense_ms", 1e3 * dense.median_s},
          {"mumps_ms", 1e3 * mumps.median_s},
          {"iterations", {{"dense", dense.iterations}, {"mumps", mumps.iterations}}},
          {"status", {{"dense", dense.status}, {"mumps", mumps.status}}},
          {"dense_ms_per_iteration", per_iteration_ms(dense)},
          {"mumps_ms_per_iteration", per_iteration_ms(mumps)},
          {"dense_over_mumps_per_iteration", per_iteration_ms(mumps) > 0 ? per_iteration_ms(dense) / per_iteration_ms(mumps) : 0.0}};
}

// The smallest KKT dimension of a sweep where the dense solver's iteration costs at least MUMPS's.
json break_even(const json& sweep) {
  for (const json& row : sweep)
    if (row["dense_over_mumps_per_iteration"].get<double>() >= 1.0) return row["kkt_dimension"];
  return nullptr;
}

}  // namespace

json ipopt_linear_solver_study(const LinearSolverStudyInputs& in, int reps) {
  json out;
  out["threshold_of_automatic"] = fpl::kDenseKktMaxDimension;
  out["condensed_threshold_of_automatic"] = fpl::kCondensedKktMaxDimension;

  // Dense LP rows: 4 coefficients (the SLP's and the quartic's exchange) and 20.
  json lp_sweep = json::array();
  for (const auto& [n, rows] : std::vector<std::pair<int, int>>{{4, 6}, {4, 22}, {4, 50}, {4, 100}, {4, 150}, {20, 60},
                                                               {20, 120}, {20, 200}, {4, 300}, {40, 300}}) {
    std::mt19937 rng(7u + static_cast<unsigned>(rows));
    const fpl::LinearProgram lp = test::random_feasible_lp(rng, n, rows);
    auto solve = [&] {
      const fpl::LinearProgramResult r = fpl::solve_linear_program(lp);
      return std::make_pair(r.iterations, r.solver_status);
    };
    const Timed dense = timed_under(IpoptLinearSolver::DenseLdlt, reps, solve);
    const Timed mumps = timed_under(IpoptLinearSolver::Mumps, reps, solve);
    json row = side_by_side(n + 2 * rows, dense, mumps);
    row["variables"] = n;
    row["rows"] = rows;
    lp_sweep.push_back(row);
  }
  out["linear_programs"] = lp_sweep;
  out["linear_programs_break_even_kkt_dimension"] = break_even(lp_sweep);

  // The collocation reference along the scenario's path: sparse KKT systems.
  fpl::OpenLoopOptions unbounded = in.open_loop;
  unbounded.sos.bounds.enforce = false;
  const fpl::JointPath path = fpl::plan_open_loop(in.flat, in.workspace, in.initial, unbounded).path;
  json collocation_sweep = json::array();
  for (int intervals : {2, 4, 8, 16}) {
    fpl::CollocationOptions co;
    co.mesh_intervals = intervals;
    int dimension = 0;
    auto solve = [&] {
      const fpl::CollocationResult r =
          fpl::solve_collocation_along_path(in.flat, in.workspace, path, in.initial, in.open_loop.reserves_N, co);
      dimension = r.variables + r.constraints;  // its rows are equalities
      return std::make_pair(r.iterations, r.solver_status);
    };
    const int collocation_reps = std::max(1, reps / 7);
    const Timed dense = timed_under(IpoptLinearSolver::DenseLdlt, collocation_reps, solve);
    const Timed mumps = timed_under(IpoptLinearSolver::Mumps, collocation_reps, solve);
    json row = side_by_side(dimension, dense, mumps);
    row["mesh_intervals"] = intervals;
    collocation_sweep.push_back(row);
  }
  out["collocation"] = collocation_sweep;
  out["collocation_break_even_kkt_dimension"] = break_even(collocation_sweep);

  // The planner's stages that call Ipopt, as before this work (MUMPS, Ipopt's getrusage timers),
  // with the timers served by flatsos, and now (those timers and the automatic linear solver).
  auto stage = [&](int stage_reps, auto f) {
    fpl::set_ipopt_timers_by_getrusage(true);
    const Timed before = timed_under(IpoptLinearSolver::Mumps, stage_reps, f);
    fpl::set_ipopt_timers_by_getrusage(false);
    const Timed timers = timed_under(IpoptLinearSolver::Mumps, stage_reps, f);
    const Timed now = timed_under(IpoptLinearSolver::Automatic, stage_reps, f);
    return json{{"before_ms", 1e3 * before.median_s},
                {"mumps_flatsos_timers_ms", 1e3 * timers.median_s},
                {"now_ms", 1e3 * now.median_s},
                {"before_over_now", before.median_s / now.median_s},
                {"ipopt_iterations", {{"before", before.iterations}, {"now", now.iterations}}},
                {"status", {{"before", before.status}, {"now", now.status}}}};
  };
  auto plan = [&](const fpl::OpenLoopOptions& o) {
    return [&in, o] {
      const fpl::OpenLoopPlan p = fpl::plan_open_loop(in.flat, in.workspace, in.initial, o);
      return std::make_pair(p.sos.ipopt_iterations, std::string(fpl::to_string(p.status)));
    };
  };
  json stages;
  stages["open_loop_sop_setup_solve_certificates"] = stage(reps, plan(in.open_loop));
  fpl::OpenLoopOptions fast = in.open_loop;
  fast.duration_s = 0.5 * in.open_loop.duration_s;
  fast.sos.flat_output_degree = 3;
  fast.sos.flat_output_spans = 24;
  fast.torque.pieces = 24;
  stages["open_loop_cubic_24_spans_half_duration_bounded"] = stage(std::max(3, reps / 10), plan(fast));
  stages["slp_by_ipopt"] = stage(reps, [&] {
    const fpl::SlpResult r = fpl::solve_slp_by_ipopt(in.slp_rows, in.slp_bounds_N);
    return std::make_pair(r.iterations, std::string(fpl::to_string(r.status)));
  });
  out["stages"] = stages;
  return out;
}

}  // namespace flatsos::bench
