#include "sos/sos_bounds.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "bounds/sequential_lp.hpp"
#include "flatsos/planner/numerics/ipopt_linear_solver.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "sos/bound_points.hpp"
#include "sos/bounds_nlp.hpp"
#include "sos/sos_exchange.hpp"

namespace flatsos::planner::detail {

namespace {
constexpr double kRoundStartRadius = 0.01;  // of the largest coefficient
// Between rounds the bounds are checked on every tenth time of the check grid, and on the whole
// grid only once that finds nothing: each time costs an inverse map (an LU of the m x m C(q)),
// and the 40-muscle leg took six rounds.
constexpr int kCoarseStride = 10;
// Each step LP starts from the violated rows and the last LP's active ones only; rows its step
// would violate join, and it is solved again from its basis (the same step). The receding
// horizon's 8 closest rows per coefficient (its 37 coefficients: about 300 rows) are, with the
// open-loop plans' 200-odd coefficients, some 1500 rows that are never active and made each LP
// slow: the arm's bounded plans at T = 3 s 138 -> 103 ms, at 1.5 s 96 -> 83 ms, the free path's
// two plans along paths 0.53 -> 0.45 s, the same plans (docs/method/sos_program.md).
constexpr int kClosestRowsPerCoefficient = 0;
constexpr const char* kBoundsUnmet =
    "no flat outputs in this basis keep every excitation in [0, 1] and activation in [a_min, 1] with the reserves";
}  // namespace

namespace {
// The torques' jets on the check grid (what the bounds need besides theta).
std::vector<TorqueJet> check_grid_jets(const SosSetup& setup, const MusclesAlongPath& mp, const BoundsSettings& bo) {
  if (bo.check_points < 2) throw std::invalid_argument("SOS program: bounds need at least 2 check points");
  const double h = setup.duration_s / (bo.check_points - 1);
  return torque_jets_on_grid(mp.flat, mp.workspace, mp.path, h, bo.check_points);
}
}  // namespace

bool check_excitation_bounds(const SosSetup& setup, const MusclesAlongPath& mp, const SosSettings& o,
                             const Eigen::VectorXd& theta, SosProgramResult& result) {
  const Stopwatch wall;
  const std::vector<TorqueJet> jets = check_grid_jets(setup, mp, o.bounds);
  const GridExcess excess =
      grid_excess(setup, mp, jets, activation_minima(mp.flat, o.bounds.min_activation), theta, o.bounds.check_points);
  result.max_bound_excess = excess.worst;
  result.bounds_seconds = wall.seconds();
  if (excess.worst <= o.bounds.tolerance) return true;
  result.status = SolveStatus::Failed;
  result.message = "the reserves' optimum leaves the excitation bounds, which this method does not impose (the "
                   "exchange does): " + excess.worst_text;
  return false;
}

bool impose_excitation_bounds(SosSetup& setup, const MusclesAlongPath& mp, const SosSettings& o,
                              Eigen::VectorXd& theta, SosProgramResult& result, SequentialLpBasis basis,
                              const BoundsWarmStart* warm) {
  const Stopwatch wall;
  if (warm) {
    if (warm->theta.size() != setup.free_coefficients || !warm->theta.allFinite())
      throw std::invalid_argument(
          "SOS program: the warm start's coefficients are not finite or not in the program's basis");
    for (double t : warm->times_s)
      if (!(t >= 0.0 && t <= setup.duration_s))
        throw std::invalid_argument("SOS program: the warm start's time " + std::to_string(t) + " s is outside [0, T]");
  }
  const BoundsSettings& bo = o.bounds;
  const FlatOutputMap& flat = mp.flat;
  const std::vector<TorqueJet> jets = check_grid_jets(setup, mp, bo);
  const Eigen::VectorXd a_min = activation_minima(flat, bo.min_activation);
  const double h = setup.duration_s / (bo.check_points - 1);

  const int stride = (bo.check_points - 1) % kCoarseStride == 0 ? kCoarseStride : 1;
  if (grid_excess(setup, mp, jets, a_min, theta, bo.check_points, stride).worst <= bo.tolerance) {
    // The bounds may not bind: the reserves' exact optimum first. Its rounds and time add to the
    // loose exchange's (this call's wall time is counted as the bounds').
    const int rounds = result.exchange_rounds;
    const double exchange_seconds = result.solve_seconds;
    const bool solved = solve_by_exchange(setup, o, theta, result, &basis);
    result.exchange_rounds += rounds;
    result.solve_seconds = exchange_seconds;
    if (!solved) {
      result.bounds_seconds = wall.seconds();
      return false;
    }
  }
  GridExcess excess = grid_excess(setup, mp, jets, a_min, theta, bo.check_points);
  result.max_bound_excess = excess.worst;
  if (excess.worst <= bo.tolerance) {
    result.bounds_seconds = wall.seconds();
    return true;
  }
  result.bounds_imposed = true;
  if (setup.free_coefficients == 0) {
    // The boundary conditions fix the flat outputs completely: nothing can move them inside.
    result.status = SolveStatus::Infeasible;
    result.message = "infeasible: the boundary conditions fix the flat outputs completely (no free coefficient in "
                     "this basis) and they leave the bounds: " + excess.worst_text;
    result.Y = flat_outputs_of(setup, theta);
    result.bounds_seconds = wall.seconds();
    return false;
  }
  std::vector<BoundPoint> points;
  auto add_point = [&](double t) {
    for (const auto& bp : points)
      if (std::abs(bp.t_s - t) < 1e-9) return false;
    points.push_back(make_point(setup, mp, t));
    return true;
  };
  // initial_points_per_span on every span (short spans get points of their own), and the ends.
  add_point(0.0);
  for (double t : setup.basis.pointsPerSpan(bo.initial_points_per_span)) add_point(t);
  if (bo.initial_points_per_span > 0) add_point(setup.duration_s);
  for (double t : violated_times(excess, h, bo.tolerance)) add_point(t);
  if (warm) {
    for (double t : warm->times_s) add_point(t);
    theta = warm->theta;
  }

  double radius = 0.1 * (1.0 + theta.cwiseAbs().maxCoeff());
  bool last_rows_violated = false;
  // The bound rows at theta of the first rows_points points: a round starts at the theta where
  // the last ended, so only the points it added need their rows (one evaluation of every point's
  // rows and Jacobian fewer per round, the same plans to the bit).
  BoundRowsAt rows_at_theta;
  std::size_t rows_points = 0;
  for (int round = 0; round < bo.max_rounds; ++round) {
    result.bound_rounds = round + 1;
    result.lp_points = build_exchange_rows(setup, o.feasibility_margin_N);
    result.bound_points = static_cast<int>(points.size());
    if (bo.solver == BoundsSolver::SequentialLp) {
      // The last round ended with a radius as small as its last step (1e-4 N and less); the
      // points this round added need moves of newtons: growing back by doubling took about ten
      // steps per round (85 steps in 9 rounds at T = 1.5 s, 33 with this floor).
      radius = std::max(radius, kRoundStartRadius * (1.0 + theta.cwiseAbs().maxCoeff()));
      SequentialLpLinearPart linear{setup.lp, {}, o.feasibility_margin_N};
      for (const auto& c : setup.constraints) linear.rows_per_group.push_back(c.points.size());
      SequentialLpSettings settings;
      settings.max_iterations = bo.max_sequential_lp_iterations;
      settings.closest_rows_per_coefficient = kClosestRowsPerCoefficient;
      append_rows(flat, points, rows_points, a_min, theta, true, kBoundMargin, rows_at_theta);
      rows_points = points.size();
      const SequentialLpOutcome slp = solve_by_sequential_lp(linear, bound_rows_of(flat, points, a_min, kBoundMargin), theta, radius,
                                                 basis, settings, &rows_at_theta);
      result.bound_sequential_lp_iterations += slp.iterations;
      result.simplex_pivots += slp.lp_pivots;
      if (!slp.converged) {
        result.status = SolveStatus::Failed;
        result.message = "the bounds were not met: " + slp.failure;
        result.bounds_seconds = wall.seconds();
        return false;
      }
      last_rows_violated = slp.rows_violated;
      // The rows at these points alone cannot be met: more points cannot help.
      if (last_rows_violated) break;
    } else {
      const IpoptBoundsOutcome nlp = solve_bounds_by_ipopt(setup, flat, points, a_min, theta, bo.max_ipopt_iterations);
      result.ipopt_iterations += nlp.iterations;
      ++result.ipopt_calls;
      add_linear_solver_name(result.ipopt_linear_solver, nlp.linear_solver);
      if (!nlp.solved) {
        const GridExcess at = nlp.x.size() ? grid_excess(setup, mp, jets, a_min, nlp.x, bo.check_points) : excess;
        result.status = nlp.infeasible ? SolveStatus::Infeasible : SolveStatus::Failed;
        result.message = std::string(nlp.infeasible ? "infeasible: " : "failed: ") + kBoundsUnmet + " (Ipopt: " +
                         nlp.solver_status + "); where it stopped, " + at.worst_text;
        result.bounds_seconds = wall.seconds();
        return false;
      }
      theta = nlp.x;
    }
    double min_reserve = 0.0;
    const bool reserves_added =
        add_violated_points(setup, theta, o.feasibility_margin_N, min_reserve, kConstraintTolerance_N, kLiftBelow_N);
    result.min_constraint_value_N = min_reserve;
    excess = grid_excess(setup, mp, jets, a_min, theta, bo.check_points, stride);
    bool bounds_added = false;
    // Every local maximum of the excess joins, not only those above the tolerance: along an arc
    // where a bound is active the dips between imposed points come back one by one otherwise.
    for (double t : violated_times(excess, h, 0.0)) bounds_added |= add_point(t);
    const bool reserves_hold_or_warm = !reserves_added || (warm && warm->whole_grid_every_round);
    if (reserves_hold_or_warm && (excess.worst <= bo.tolerance || !bounds_added) && stride > 1) {
      // Nothing left that the coarse grid sees: the whole grid decides (BoundsWarmStart).
      excess = grid_excess(setup, mp, jets, a_min, theta, bo.check_points);
      for (double t : violated_times(excess, h, 0.0)) bounds_added |= add_point(t);
    }
    result.max_bound_excess = excess.worst;
    if (!reserves_added && excess.worst <= bo.tolerance && excess.stride == 1) {
      result.bounds_seconds = wall.seconds();
      return true;
    }
    if (!reserves_added && !bounds_added) break;  // violations at points already imposed: tolerance
  }
  result.bounds_seconds = wall.seconds();
  if (last_rows_violated) {
    // A local minimum of the violation, even at a penalty of 1e12 per unit: the flat outputs of
    // this basis cannot meet the bounds along this joint path (from this start).
    result.status = SolveStatus::Infeasible;
    result.message = std::string("infeasible: ") + kBoundsUnmet + " along this joint path";
    result.Y = flat_outputs_of(setup, theta);  // the closest plan, for the caller's diagnosis
    return false;
  }
  result.status = SolveStatus::Failed;
  result.message = "the bounded exchange did not converge in " + std::to_string(result.bound_rounds) +
                   " rounds (worst bound excess " + std::to_string(excess.worst) + ": " + excess.worst_text + ")";
  return false;
}

}  // namespace flatsos::planner::detail
