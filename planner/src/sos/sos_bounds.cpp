#include "sos/sos_bounds.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

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

namespace {

void require_warm_start_of(const SosSetup& setup, const BoundsWarmStart& warm) {
  if (warm.theta.size() != setup.free_coefficients || !warm.theta.allFinite())
    throw std::invalid_argument("SOS program: the warm start's coefficients are not finite or not in the program's basis");
  for (double t : warm.times_s)
    if (!(t >= 0.0 && t <= setup.duration_s))
      throw std::invalid_argument("SOS program: the warm start's time " + std::to_string(t) + " s is outside [0, T]");
}

// One impose_excitation_bounds call: rounds that impose the bounds at their points (by the
// sequential LP or Ipopt) and add the check grid's violations as points.
class BoundedExchange {
 public:
  BoundedExchange(SosSetup& setup, const MusclesAlongPath& mp, const SosSettings& o, Eigen::VectorXd& theta,
                  SosProgramResult& result, SequentialLpBasis basis, const BoundsWarmStart* warm)
      : setup_(setup), mp_(mp), flat_(mp.flat), o_(o), bo_(o.bounds), theta_(theta), result_(result),
        basis_(std::move(basis)), warm_(warm), jets_(check_grid_jets(setup, mp, o.bounds)),
        a_min_(activation_minima(mp.flat, o.bounds.min_activation)), h_(setup.duration_s / (o.bounds.check_points - 1)),
        stride_((o.bounds.check_points - 1) % kCoarseStride == 0 ? kCoarseStride : 1) {}

  bool run() {
    if (!reservesOptimumWhereTheBoundsMayNotBind()) return done(false);
    excess_ = grid_excess(setup_, mp_, jets_, a_min_, theta_, bo_.check_points);
    result_.max_bound_excess = excess_.worst;
    if (excess_.worst <= bo_.tolerance) return done(true);
    result_.bounds_imposed = true;
    if (setup_.free_coefficients == 0) {
      // The boundary conditions fix the flat outputs completely: nothing can move them inside.
      result_.status = SolveStatus::Infeasible;
      result_.message = "infeasible: the boundary conditions fix the flat outputs completely (no free coefficient in "
                        "this basis) and they leave the bounds: " + excess_.worst_text;
      result_.Y = flat_outputs_of(setup_, theta_);
      return done(false);
    }
    addInitialPoints();
    radius_ = 0.1 * (1.0 + theta_.cwiseAbs().maxCoeff());
    for (int round = 0; round < bo_.max_rounds; ++round) {
      result_.bound_rounds = round + 1;
      result_.lp_points = build_exchange_rows(setup_, o_.feasibility_margin_N);
      result_.bound_points = static_cast<int>(points_.size());
      const bool imposed = bo_.solver == BoundsSolver::SequentialLp ? roundBySequentialLp() : roundByIpopt();
      if (!imposed) return done(false);
      if (last_rows_violated_) break;  // the rows at these points alone cannot be met: more points cannot help
      switch (addViolations()) {
        case Check::Holds: return done(true);
        case Check::NothingNew: break;
        case Check::PointsAdded: continue;
      }
      break;
    }
    result_.bounds_seconds = wall_.seconds();
    return notMet();
  }

 private:
  enum class Check { Holds, NothingNew, PointsAdded };

  bool done(bool met) {
    result_.bounds_seconds = wall_.seconds();
    return met;
  }

  // Where the coarse grid sees no violation, the bounds may not bind: the reserves' exact optimum
  // first. Its rounds and time add to the loose exchange's (this call's wall time is counted as
  // the bounds').
  bool reservesOptimumWhereTheBoundsMayNotBind() {
    if (grid_excess(setup_, mp_, jets_, a_min_, theta_, bo_.check_points, stride_).worst > bo_.tolerance) return true;
    const int rounds = result_.exchange_rounds;
    const double exchange_seconds = result_.solve_seconds;
    const bool solved = solve_by_exchange(setup_, o_, theta_, result_, &basis_);
    result_.exchange_rounds += rounds;
    result_.solve_seconds = exchange_seconds;
    return solved;
  }

  bool addPoint(double t) {
    for (const auto& bp : points_)
      if (std::abs(bp.t_s - t) < 1e-9) return false;
    points_.push_back(make_point(setup_, mp_, t));
    return true;
  }

  // initial_points_per_span on every span (short spans get points of their own), the ends, the
  // violations, and a warm start's points (theta starts there too).
  void addInitialPoints() {
    addPoint(0.0);
    for (double t : setup_.basis.pointsPerSpan(bo_.initial_points_per_span)) addPoint(t);
    if (bo_.initial_points_per_span > 0) addPoint(setup_.duration_s);
    for (double t : violated_times(excess_, h_, bo_.tolerance)) addPoint(t);
    if (!warm_) return;
    for (double t : warm_->times_s) addPoint(t);
    theta_ = warm_->theta;
  }

  bool roundBySequentialLp() {
    // The last round ended with a radius as small as its last step (1e-4 N and less); the points
    // this round added need moves of newtons: growing back by doubling took about ten steps per
    // round (85 steps in 9 rounds at T = 1.5 s, 33 with this floor).
    radius_ = std::max(radius_, kRoundStartRadius * (1.0 + theta_.cwiseAbs().maxCoeff()));
    SequentialLpLinearPart linear{setup_.lp, {}, o_.feasibility_margin_N};
    for (const auto& c : setup_.constraints) linear.rows_per_group.push_back(c.points.size());
    SequentialLpSettings settings;
    settings.max_iterations = bo_.max_sequential_lp_iterations;
    settings.closest_rows_per_coefficient = kClosestRowsPerCoefficient;
    // The bound rows at theta of the first rows_points_ points: a round starts at the theta where
    // the last ended, so only the points it added need their rows.
    append_rows(flat_, points_, rows_points_, a_min_, theta_, true, kBoundMargin, rows_at_theta_);
    rows_points_ = points_.size();
    const SequentialLpOutcome slp = solve_by_sequential_lp(linear, bound_rows_of(flat_, points_, a_min_, kBoundMargin),
                                                           theta_, radius_, basis_, settings, &rows_at_theta_);
    result_.bound_sequential_lp_iterations += slp.iterations;
    result_.bound_slp_iterations = result_.bound_sequential_lp_iterations;
    result_.simplex_pivots += slp.lp_pivots;
    if (!slp.converged) {
      result_.status = SolveStatus::Failed;
      result_.message = "the bounds were not met: " + slp.failure;
      return false;
    }
    last_rows_violated_ = slp.rows_violated;
    return true;
  }

  bool roundByIpopt() {
    const IpoptBoundsOutcome nlp = solve_bounds_by_ipopt(setup_, flat_, points_, a_min_, theta_, bo_.max_ipopt_iterations);
    result_.ipopt_iterations += nlp.iterations;
    ++result_.ipopt_calls;
    add_linear_solver_name(result_.ipopt_linear_solver, nlp.linear_solver);
    if (nlp.solved) {
      theta_ = nlp.x;
      return true;
    }
    const GridExcess at = nlp.x.size() ? grid_excess(setup_, mp_, jets_, a_min_, nlp.x, bo_.check_points) : excess_;
    result_.status = nlp.infeasible ? SolveStatus::Infeasible : SolveStatus::Failed;
    result_.message = std::string(nlp.infeasible ? "infeasible: " : "failed: ") + kBoundsUnmet + " (Ipopt: " +
                      nlp.solver_status + "); where it stopped, " + at.worst_text;
    return false;
  }

  // The reserves' and the bounds' violations at theta become points of the next round.
  Check addViolations() {
    double min_reserve = 0.0;
    const bool reserves_added =
        add_violated_points(setup_, theta_, o_.feasibility_margin_N, min_reserve, kConstraintTolerance_N, kLiftBelow_N);
    result_.min_constraint_value_N = min_reserve;
    excess_ = grid_excess(setup_, mp_, jets_, a_min_, theta_, bo_.check_points, stride_);
    bool bounds_added = false;
    // Every local maximum of the excess joins, not only those above the tolerance: along an arc
    // where a bound is active the dips between imposed points come back one by one otherwise.
    for (double t : violated_times(excess_, h_, 0.0)) bounds_added |= addPoint(t);
    // Once the reserves' dips are no deeper than the lift takes (kLiftBelow_N), the plan moves
    // little more: the violations only the whole grid sees stay where it finds them, and their
    // points join beside the last dips' instead of a round after them (the arm at T = 1.5 s: 11
    // -> 6 rounds, 111 -> 86 ms; at 3 s 6 -> 5 rounds, 68 -> 66 ms).
    const bool plan_settling = min_reserve >= -kLiftBelow_N;
    const bool whole_grid_due = !reserves_added || plan_settling || (warm_ && warm_->whole_grid_every_round);
    if (whole_grid_due && (excess_.worst <= bo_.tolerance || !bounds_added) && stride_ > 1) {
      // Nothing left that the coarse grid sees: the whole grid decides (BoundsWarmStart).
      excess_ = grid_excess(setup_, mp_, jets_, a_min_, theta_, bo_.check_points);
      for (double t : violated_times(excess_, h_, 0.0)) bounds_added |= addPoint(t);
    }
    result_.max_bound_excess = excess_.worst;
    if (!reserves_added && excess_.worst <= bo_.tolerance && excess_.stride == 1) return Check::Holds;
    if (!reserves_added && !bounds_added) return Check::NothingNew;  // violations at points already imposed: tolerance
    return Check::PointsAdded;
  }

  bool notMet() {
    if (last_rows_violated_) {
      // A local minimum of the violation, even at a penalty of 1e12 per unit: the flat outputs of
      // this basis cannot meet the bounds along this joint path (from this start).
      result_.status = SolveStatus::Infeasible;
      result_.message = std::string("infeasible: ") + kBoundsUnmet + " along this joint path";
      result_.Y = flat_outputs_of(setup_, theta_);  // the closest plan, for the caller's diagnosis
      return false;
    }
    result_.status = SolveStatus::Failed;
    result_.message = "the bounded exchange did not converge in " + std::to_string(result_.bound_rounds) + " rounds (" +
                      (excess_.worst_text.empty() ? std::string("the bounds held; each round still added reserve points")
                                                  : "worst bound excess " + std::to_string(excess_.worst) + ": " +
                                                        excess_.worst_text) +
                      ")";
    return false;
  }

  const Stopwatch wall_;
  SosSetup& setup_;
  const MusclesAlongPath& mp_;
  const FlatOutputMap& flat_;
  const SosSettings& o_;
  const BoundsSettings& bo_;
  Eigen::VectorXd& theta_;
  SosProgramResult& result_;
  SequentialLpBasis basis_;
  const BoundsWarmStart* warm_;
  const std::vector<TorqueJet> jets_;
  const Eigen::VectorXd a_min_;
  const double h_;
  const int stride_;
  GridExcess excess_;
  std::vector<BoundPoint> points_;
  double radius_ = 0.0;
  bool last_rows_violated_ = false;
  BoundRowsAt rows_at_theta_;
  std::size_t rows_points_ = 0;
};

}  // namespace

bool impose_excitation_bounds(SosSetup& setup, const MusclesAlongPath& mp, const SosSettings& o,
                              Eigen::VectorXd& theta, SosProgramResult& result, SequentialLpBasis basis,
                              const BoundsWarmStart* warm) {
  if (warm) require_warm_start_of(setup, *warm);
  return BoundedExchange(setup, mp, o, theta, result, std::move(basis), warm).run();
}

}  // namespace flatsos::planner::detail
