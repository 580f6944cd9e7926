#include "receding_horizon/period_bounds.hpp"

#include <algorithm>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "bounds/bound_rows.hpp"
#include "bounds/sequential_lp.hpp"
#include "bounds/point_rows.hpp"
#include "bounds/active_set_newton.hpp"

namespace flatsos::planner::detail {

constexpr double kReserveMargin_N = 1e-6;
// The bounds' sequential LP stops once an LP step would lower the effort by less than this
// fraction: near the bounded optimum its trust region halves step after step (linear
// convergence on curved active bounds), 204 LP steps over the leg's 30 periods to gain the last
// 1e-5; the plan is replaced a period later. 108 steps with it, the closed loop's end within
// 4e-4 deg of the exact one's.
constexpr double kBoundsLpRelativeDecrease = 1e-5;

namespace {
double sample_spacing_s(const PeriodExcitationBounds& b) { return b.period_s / (b.samples - 1); }
}  // namespace

bool sample_period(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const PeriodExcitationBounds& b,
                   RecedingHorizonStep& step) {
  auto& buf = step.buffers;
  return sample_plan_excitations(flat, workspace, step.path, step.alpha(), step.torque_offset_N_m, 0.0, sample_spacing_s(b),
                                 b.samples, buf.period, buf.excitations, &buf.activations, &step.flat_start);
}

void muscle_torques(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const RecedingHorizonOptions& o,
                    const RecedingHorizonStep& step, double h_s, int count, TorqueJetGrid& grid) {
  flat.torqueJetsOnGrid(
      workspace, [&](double t, Jet& jet) { rest_held_jet(step.path, t, jet); }, 0.0, h_s, count, grid);
  if (o.torque_offset_N_m.size())
    for (TorqueJet& tj : grid.jets) tj.tau.col(0) -= o.torque_offset_N_m;
}

SampleExcess worst_excess(const FlatOutputMap& flat, const RecedingHorizonStep& step) {
  SampleExcess worst;
  const Eigen::MatrixXd &n = step.buffers.excitations, &a = step.buffers.activations;
  for (int j = 0; j < flat.numMuscles(); ++j) {
    const double floor = flat.model().muscle(j).getParameters().activation_floor;
    for (Eigen::Index i = 0; i < n.rows(); ++i) {
      const double e = std::max({floor - a(i, j), a(i, j) - 1.0, -n(i, j), n(i, j) - 1.0});
      if (e > worst.value) worst = {e, static_cast<int>(i), j};
    }
  }
  return worst;
}

namespace {
std::string describe(const FlatOutputMap& flat, const PeriodExcitationBounds& b, const RecedingHorizonStep& step,
                     const SampleExcess& e) {
  std::ostringstream why;
  why << "muscle '" << flat.model().muscle(e.muscle).getParameters().name << "' at t = " << sample_spacing_s(b) * e.sample
      << " s: activation " << step.buffers.activations(e.sample, e.muscle) << ", excitation "
      << step.buffers.excitations(e.sample, e.muscle);
  return why.str();
}

// The violation that made the sampling stop (its last point).
std::string domain_violation(const FlatOutputMap& flat, const RecedingHorizonStep& step) {
  const std::vector<DomainViolation>& v = step.buffers.period.point.domain_violation;
  for (std::size_t j = 0; j < v.size(); ++j)
    if (v[j].violated()) return "muscle '" + flat.model().muscle(static_cast<int>(j)).getParameters().name + "': " + v[j].describe();
  return "an excitation is not finite";
}

// The bounds' sequential LP from alpha (moved to where it ends), in a trust box a tenth of its
// size, restarted from the step's last LP basis.
// `rows_at_alpha`: rows(alpha, true) when already evaluated.
SequentialLpOutcome bounds_lp(const SequentialLpLinearPart& linear, const NonlinearRows& rows, int max_iterations,
                              RecedingHorizonStep& step, Eigen::VectorXd& alpha, BoundRowsAt* rows_at_alpha = nullptr) {
  double radius = 0.1 * (1.0 + alpha.cwiseAbs().maxCoeff());
  SequentialLpSettings settings;
  settings.max_iterations = max_iterations;
  settings.relative_decrease = kBoundsLpRelativeDecrease;
  settings.back_off = true;
  return solve_by_sequential_lp(linear, rows, alpha, radius, step.buffers.bounds_basis, settings, rows_at_alpha);
}

}  // namespace

bool sampled_at_points(const FlatOutputMap& flat, const std::vector<BoundPoint>& points, RecedingHorizonStep& step) {
  auto& buf = step.buffers;
  step.first_period_sampled =
      point_excitations(flat, points, step.alpha(), buf.excitations, buf.activations) && worst_excess(flat, step).value <= 0.0;
  return step.first_period_sampled;
}

namespace {

// After the bounds moved alpha (step.slp.alpha; by the sequential LP or Newton's method on an
// active set): samples the first period and says what holds there; `rows_violated`: the sequential
// LP settled with rows it could not meet; `at_points`: the step's buffers already hold the points'
// excitations and activations for alpha (Newton's last evaluation).
void check_bounded_samples(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const PeriodExcitationBounds& b,
                           const std::vector<BoundPoint>& points, bool rows_violated, bool at_points,
                           RecedingHorizonStep& step) {
  step.first_period_sampled = at_points ? worst_excess(flat, step).value <= 0.0 : sampled_at_points(flat, points, step);
  if (step.first_period_sampled) return;
  // Otherwise the plan itself, sampled as before the bounds: what holds there, and the message.
  const bool finite = sample_period(flat, workspace, b, step);
  const SampleExcess left = finite ? worst_excess(flat, step) : SampleExcess{};
  if (finite && left.value <= 0.0) {
    // Every sample inside, even where a row's margin was not quite reached: what is applied holds.
    step.first_period_sampled = true;
  } else if (rows_violated) {
    step.status = SolveStatus::Infeasible;
    step.message = "infeasible: no constant flat outputs keep every excitation in [0, 1] and activation in [floor, 1] "
                   "over the first period with the reserves" +
                   (finite ? "; closest: " + describe(flat, b, step, left) : std::string());
  } else if (!finite) {
    step.status = SolveStatus::Failed;
    step.message = "the alpha that meets the excitation bounds' rows leaves the model's valid domain on the first period: " +
                   domain_violation(flat, step);
  } else {
    step.status = SolveStatus::Failed;
    step.message = "the alpha that meets the excitation bounds' rows still leaves them on the first period's samples: " +
                   describe(flat, b, step, left);
  }
}

// Newton's method on the active set `active` from alpha over the points' bound rows, the reserve rows and
// alpha >= 0 (bounds/active_set_newton.hpp). Solved, the step's buffers take the points'
// excitations and activations at the final alpha from its last evaluation when it has them
// (`at_points`): the same inverse point_excitations would compute again.
ActiveSetNewtonOutcome newton_on_active_set(const FlatOutputMap& flat, const std::vector<BoundPoint>& points,
                                     const Eigen::VectorXd& a_min, const SequentialLpLinearPart& linear,
                                     std::vector<int>& active, Eigen::VectorXd& alpha, RecedingHorizonStep& step,
                                     bool& at_points) {
  PointRows point_rows(flat, points, a_min, kSampleMargin);
  WithLinearRows with_reserves(point_rows, linear.lp);
  with_reserves.evaluate(alpha, true);
  const ActiveSetNewtonOutcome out = solve_on_active_set(linear, with_reserves, active, alpha);
  at_points = out.solved && point_rows.inverseAt(alpha, step.buffers.excitations, step.buffers.activations);
  return out;
}

}  // namespace

std::vector<BoundPoint> step_points(const FlatOutputMap& flat, const RecedingHorizonStep& step, const TorqueJetGrid& grid,
                                    double h_s, int count) {
  const int m = flat.numMuscles(), p = flat.numFlatOutputs();
  std::vector<BoundPoint> points(static_cast<std::size_t>(count));
  Jet q_jet(flat.numJoints(), 3);
  Eigen::MatrixXd cy1, cy2;  // C_Y's rates at a point
  for (int i = 0; i < count; ++i) {
    BoundPoint& bp = points[static_cast<std::size_t>(i)];
    bp.t_s = h_s * i;
    const TorqueJet& tau = grid.jets[static_cast<std::size_t>(i)];
    rest_held_jet(step.path, bp.t_s, q_jet);
    const ForceJetMap map = flat.forceJetMap(q_jet);
    bp.base = map.Ctau * tau.tau;
    for (int c = 0; c < p; ++c) bp.columns.push_back(c);
    // Y^(k) = c^(k) alpha + (phi0 Y0 + phi1 Y0')^(k) with c = 1 - phi0 (c = 1 without a start):
    // the start's part joins the base, and alpha's columns are the jet of c C_Y.
    double c[3] = {1.0, 0.0, 0.0};
    if (!step.flat_start.empty()) {
      double phi0[3], phi1[3];
      step.flat_start.blend(bp.t_s, 0, phi0);
      step.flat_start.blend(bp.t_s, 1, phi1);
      for (int k = 0; k < 3; ++k) {
        c[k] = (k == 0 ? 1.0 : 0.0) - phi0[k];
        bp.base.col(k) += map.CY * (phi0[k] * step.flat_start.value + phi1[k] * step.flat_start.rate);
      }
    }
    map.flatOutputColumnRates(cy1, cy2);
    bp.slope = {c[0] * map.CY, c[1] * map.CY + c[0] * cy1, c[2] * map.CY + 2.0 * c[1] * cy1 + c[0] * cy2};
    if (map.varies()) {
      Eigen::MatrixXd b0 = bp.base.col(0), b1 = bp.base.col(1), b2 = bp.base.col(2);
      map.mix(b0, b1, b2);
      bp.base << b0, b1, b2;
    }
    for (int j = 0; j < m; ++j) bp.path.push_back(flat.pathLengthJet(j, q_jet));
  }
  return points;
}

std::vector<BoundPoint> period_points(const FlatOutputMap& flat, const PeriodExcitationBounds& b,
                                      const RecedingHorizonStep& step) {
  return step_points(flat, step, step.buffers.period.torque_grid, sample_spacing_s(b), b.samples);
}

namespace {
// The first period's samples for step.alpha() into the step's buffers; false where they leave
// the valid domain. With posture-dependent moment arms after a bounded step (the next is likely
// bounded too: every one of the leg's) from the bound points the bounds need anyway, into
// `points`, instead of sampling the plan and then forming the points at the same samples
// (sampling allocates there too; with constant moment arms it does not, and a step whose plan
// meets its bounds stays allocation-free). The plan is sampled where a point fails, for the
// domain's message.
bool sample_first_period(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const RecedingHorizonOptions& o,
                         RecedingHorizonStep& step, std::vector<BoundPoint>& points) {
  const PeriodExcitationBounds& b = o.excitation_bounds;
  const Eigen::VectorXd& last_bounded = step.buffers.bounded_alpha;
  if (!flat.hasConstantMomentArms() && last_bounded.size() == flat.numFlatOutputs() && last_bounded.allFinite()) {
    muscle_torques(flat, workspace, o, step, sample_spacing_s(b), b.samples, step.buffers.period.torque_grid);
    points = period_points(flat, b, step);
    auto& buf = step.buffers;
    if (point_excitations(flat, points, step.alpha(), buf.excitations, buf.activations)) return true;
  }
  return sample_period(flat, workspace, b, step);
}
}  // namespace

void impose_period_bounds(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const RecedingHorizonOptions& o,
                          int max_iterations,
                          RecedingHorizonStep& step) {
  step.bounds_imposed = false;
  step.bound_iterations = 0;
  step.bound_newton_steps = 0;
  step.bound_lp_pivots = 0;
  step.first_period_sampled = false;
  const PeriodExcitationBounds& b = o.excitation_bounds;
  if (!b.enforce || step.status != SolveStatus::Solved) return;
  const int p = flat.numFlatOutputs();
  std::vector<BoundPoint> points;
  if (!sample_first_period(flat, workspace, o, step, points)) {
    // Outside the valid domain (a too fast fibre, an unattainable excitation): no bound rows to
    // move alpha by from there, and nothing the muscles could execute.
    step.status = SolveStatus::Failed;
    step.message = "the plan leaves the model's valid domain on the first period: " + domain_violation(flat, step);
    return;
  }
  if (worst_excess(flat, step).value <= 0.0) {
    step.first_period_sampled = true;
    return;
  }

  step.bounds_imposed = true;
  if (points.empty()) points = period_points(flat, b, step);
  LinearProgram lp;
  lp.cost = step.buffers.slp.costVector(p);
  lp.G = step.reserve_rows;
  lp.row_lower = step.bound_N;
  lp.row_upper = Eigen::VectorXd::Constant(step.bound_N.size(), 1e19);
  lp.x_lower = Eigen::VectorXd::Zero(p);
  lp.x_upper = Eigen::VectorXd::Constant(p, 1e19);
  const SequentialLpLinearPart linear{lp, {static_cast<std::size_t>(step.bound_N.size())}, kReserveMargin_N};
  const Eigen::VectorXd a_min = activation_minima(flat, 0.0);
  const NonlinearRows rows = bound_rows_of(flat, points, a_min, kSampleMargin);
  const Eigen::VectorXd& unbounded = step.slp.alpha;  // unchanged until the end
  const Eigen::VectorXd& previous = step.buffers.bounded_alpha;
  const bool has_previous = previous.size() == p && previous.allFinite();
  // Newton's method on the last period's active set first: where its active rows are still the
  // optimum's, or rows join it by a few pivots, the step ends there; otherwise the sequential LP
  // starts from the point it reached (when it converged).
  std::vector<int>& active = step.buffers.bounds_active_set;
  Eigen::VectorXd alpha = previous;
  bool at_points = false;
  const ActiveSetNewtonOutcome newton = has_previous && !active.empty()
                                         ? newton_on_active_set(flat, points, a_min, linear, active, alpha, step, at_points)
                                         : ActiveSetNewtonOutcome{};
  step.bound_newton_steps = newton.iterations;
  if (newton.solved) {
    step.slp.alpha = alpha;
    step.slp.cost_N = lp.cost.dot(alpha);
    step.buffers.bounded_alpha = alpha;
    check_bounded_samples(flat, workspace, b, points, false, at_points, step);
    return;
  }
  BoundRowsAt at_previous;
  if (has_previous && !newton.converged) at_previous = rows(previous, true);
  // Else from the previous bounded step's alpha when it violates less than the SLP's optimum:
  // consecutive periods' problems differ little, so a few LP steps remain instead of the whole
  // way from the unbounded optimum (measured on the seated knee: 6-7 LP steps to 2-3). Its rows
  // were evaluated with their Jacobian, which the sequential LP then starts from.
  const bool from_previous = !newton.converged && has_previous &&
                             at_previous.violation + reserve_violation_N(lp, previous) <
                                 rows(unbounded, false).violation + reserve_violation_N(lp, unbounded);
  if (!newton.converged) alpha = from_previous ? previous : unbounded;
  SequentialLpOutcome slp = bounds_lp(linear, rows, max_iterations, step, alpha, from_previous ? &at_previous : nullptr);
  if (!slp.converged || slp.rows_violated) {
    // A stationary point of the violation is only local. The SLP's optimum sits on a vertex of
    // the reserve rows (most flat outputs at their reserve), from where the iteration can walk
    // into a co-contraction that no step leaves while feasible flat outputs exist elsewhere.
    // Once more from the optimum raised by its mean: inside the reserves, every muscle loaded.
    Eigen::VectorXd raised = unbounded.array() + std::max(unbounded.mean(), 1.0);
    SequentialLpOutcome again = bounds_lp(linear, rows, max_iterations, step, raised);
    again.iterations += slp.iterations;
    again.lp_pivots += slp.lp_pivots;
    if (again.converged && !again.rows_violated) {
      slp = std::move(again);
      alpha = raised;
    } else {
      slp.iterations = again.iterations;
      slp.lp_pivots = again.lp_pivots;
    }
  }
  step.bound_iterations = slp.iterations;
  step.bound_lp_pivots = slp.lp_pivots;
  step.slp.alpha = alpha;
  step.slp.cost_N = lp.cost.dot(alpha);
  active = active_rows(slp, alpha, lp.x_lower);
  if (slp.converged && !slp.rows_violated) step.buffers.bounded_alpha = alpha;  // never start from a stuck point
  if (!slp.converged) {
    step.status = SolveStatus::Failed;
    step.message = "the excitation bounds on the first period were not met: " + slp.failure;
    return;
  }
  check_bounded_samples(flat, workspace, b, points, slp.rows_violated, false, step);
}

}  // namespace flatsos::planner::detail
