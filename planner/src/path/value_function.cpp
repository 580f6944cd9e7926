#include "path/value_function.hpp"

#include <algorithm>
#include <utility>

#include "bounds/effort_sqp.hpp"

namespace flatsos::planner::detail {

namespace {
constexpr double kRoundStartRadius =
    0.01;  // the SLP's trust radius after new points, of the largest coefficient
}  // namespace

// For a fixed path c, the plan's rows at the points over theta alone: the bound rows (nonlinear)
// and the linear rows, group-major as the SLP's basis keys them: a group per muscle (F_j >=
// reserve_j), then a group per flat output (Y_l >= 0), a row per point in each.
struct RowsAlongPath {
  std::vector<BoundPoint> bound_points;
  LinearProgram lp;
  std::vector<std::size_t> rows_per_group;
};

static RowsAlongPath rows_along_path(const SosSetup& setup, const FlatOutputMap& flat,
                                     const std::vector<PathPoint>& points, const Eigen::VectorXd& c,
                                     const Eigen::VectorXd& reserves) {
  const int m = flat.numMuscles(), p = flat.numFlatOutputs();
  const auto count = static_cast<Eigen::Index>(points.size());
  RowsAlongPath out;
  out.bound_points = bound_points_along_path(flat, points, c);
  LinearProgram& lp = out.lp;
  lp.cost = setup.lp.cost;
  lp.x_lower = setup.lp.x_lower;
  lp.x_upper = setup.lp.x_upper;
  lp.G = Eigen::MatrixXd::Zero(count * (m + p), setup.free_coefficients);
  lp.row_lower.resize(lp.G.rows());
  lp.row_upper = Eigen::VectorXd::Constant(lp.G.rows(), 1e19);
  for (int j = 0; j < m; ++j)
    for (Eigen::Index k = 0; k < count; ++k) {
      const BoundPoint& bp = out.bound_points[static_cast<std::size_t>(k)];
      const Eigen::Index row = j * count + k;
      for (std::size_t col = 0; col < bp.columns.size(); ++col)
        lp.G(row, bp.columns[col]) = bp.slope[0](j, static_cast<Eigen::Index>(col));
      lp.row_lower[row] =
          reserves[j] + reserve_margin_N(points[static_cast<std::size_t>(k)]) - bp.base(j, 0);
    }
  for (int l = 0; l < p; ++l) {
    const OutputParameterization& y = setup.outputs[static_cast<std::size_t>(l)];
    for (Eigen::Index k = 0; k < count; ++k) {
      const Eigen::RowVectorXd b =
          setup.basis.derivativeRow(points[static_cast<std::size_t>(k)].flat.t_s, 0);
      const Eigen::Index row = (m + l) * count + k;
      if (y.nullspace.cols()) lp.G.block(row, y.offset, 1, y.nullspace.cols()) = b * y.nullspace;
      lp.row_lower[row] = -b.dot(y.particular);
    }
  }
  out.rows_per_group.assign(static_cast<std::size_t>(m + p), static_cast<std::size_t>(count));
  return out;
}

ValueFunction::ValueFunction(const SosSetup& setup, const FlatOutputMap& flat,
                             const std::vector<PathPoint>& points, const PathParameterization& P,
                             const Eigen::VectorXd& reserves, const Eigen::VectorXd& a_min,
                             int max_sequential_lp_iterations, const PathEffort* effort)
    : setup_(setup),
      flat_(flat),
      points_(points),
      reserves_(reserves),
      a_min_(a_min),
      max_slp_(max_sequential_lp_iterations),
      effort_(effort) {
  v_.thetas = setup.free_coefficients;
  v_.paths = P.free;
}

// Starts the plan's SLP from `from` (theta, basis, radius).
Evaluation ValueFunction::operator()(const Eigen::VectorXd& c, const Evaluation& from) {
  ++evaluations;
  Evaluation e;
  e.c = c;
  e.theta = from.theta;
  e.basis = from.basis;
  e.effort_rows = from.effort_rows;
  // A new path moves the rows by up to newtons: a radius as small as the last converged step
  // would take many doublings to grow back (as after the exchange's new points).
  e.radius = std::max(from.radius, kRoundStartRadius * (1.0 + e.theta.cwiseAbs().maxCoeff()));
  const RowsAlongPath rows = rows_along_path(setup_, flat_, points_, c, reserves_);
  if (effort_) return minimizeEffort(rows, std::move(e));
  const SequentialLpLinearPart linear{rows.lp, rows.rows_per_group, kReserveMargin_N};
  // Every candidate row in each step LP (no working set): the path's quasi-Newton steps follow
  // the multipliers of degenerate step LPs, and with the working set's other optimal vertices
  // they stopped 0.1 % higher on the arm (281.4 against 281.1 N s, at a point a random move
  // of 0.01 rad still lowers by 1.3e-4).
  SequentialLpSettings settings;
  settings.max_iterations = max_slp_;
  settings.working_set = false;
  const SequentialLpOutcome slp =
      solve_by_sequential_lp(linear, bound_rows_of(flat_, rows.bound_points, a_min_, kBoundMargin),
                             e.theta, e.radius, e.basis, settings);
  e.sequential_lp_iterations = slp.iterations;
  sequential_lp_iterations += slp.iterations;
  if (!slp.converged || slp.rows_violated) {
    e.failure = slp.rows_violated ? "the rows cannot be met at every point" : slp.failure;
    return e;
  }
  e.ok = true;
  e.cost_N_s = setup_.cost_constant + setup_.lp.cost.dot(e.theta);
  e.gradient = gradient(e.c, e.theta, slp.row_multipliers, slp.linear_row_multipliers);
  countActive(slp.row_multipliers, slp.linear_row_multipliers, e);
  return e;
}

// The nonlinear effort's V(c): its sequential QP from e.theta at the rows along the path, and
// dV/dc = dE/dc (theta fixed) - sum_k lambda_k d g_k / d c.
Evaluation ValueFunction::minimizeEffort(const RowsAlongPath& rows, Evaluation e) {
  const std::vector<BoundPoint> effort_points = effort_->boundPoints(e.c);
  const EffortSqpProblem problem{
      flat_,   effort_->effort(),      effort_points,     effort_->weights_s(),
      rows.lp, 0.5 * kReserveMargin_N, rows.bound_points, a_min_};
  EffortSqp sqp(problem);
  if (!sqp.start(e.theta)) {
    e.failure = "the effort '" + effort_->effort().name() +
                "' is not defined at the start of its sequential QP";
    return e;
  }
  sqp.startFrom(std::move(e.effort_rows));
  const bool solved = sqp.descend(e.theta, e.sequential_lp_iterations, max_slp_);
  e.effort_rows = sqp.activeRows();
  e.effort_qp_row_changes = sqp.qpRowChanges();
  sequential_lp_iterations += e.sequential_lp_iterations;
  Eigen::VectorXd z(v_.size()), effort_gradient;
  z << e.theta, e.c;
  if (!solved || !effort_->gradient(z, effort_gradient)) {
    e.failure = solved ? "the effort's gradient is not defined" : sqp.failure();
    return e;
  }
  e.ok = true;
  e.cost_N_s = sqp.model().value;
  e.gradient = effort_gradient.tail(v_.paths) +
               gradient(e.c, e.theta, sqp.boundRowMultipliers(), sqp.linearRowMultipliers());
  countActive(sqp.boundRowMultipliers(), sqp.linearRowMultipliers(), e);
  return e;
}

void ValueFunction::countActive(const std::vector<double>& bound, const Eigen::VectorXd& linear,
                                Evaluation& e) {
  for (double l : bound) e.active_bound_rows += l > 0.0;
  for (Eigen::Index r = 0; r < linear.size(); ++r) e.active_reserve_rows += linear[r] > 0.0;
}

// -sum_k lambda_k d g_k / d c over the rows that depend on c (reserves and bounds), at the
// points where some multiplier is not zero: `bound` per point, muscle and bound row, `linear`
// per row of rows_along_path's LP.
Eigen::VectorXd ValueFunction::gradient(const Eigen::VectorXd& c, const Eigen::VectorXd& theta,
                                        const std::vector<double>& bound,
                                        const Eigen::VectorXd& linear) const {
  const int m = flat_.numMuscles();
  const std::size_t count = points_.size();
  constexpr int kRows = PathRows::kRows;
  std::vector<double> lambda(count * static_cast<std::size_t>(m * kRows), 0.0);  // PathRows' layout
  for (std::size_t i = 0; i < bound.size(); ++i) {
    const std::size_t point_muscle = i / kRowsPerMuscle, k = i % kRowsPerMuscle;
    lambda[point_muscle * kRows + 1 + k] = bound[i];
  }
  for (int j = 0; j < m; ++j)
    for (std::size_t k = 0; k < count; ++k)
      lambda[(k * static_cast<std::size_t>(m) + static_cast<std::size_t>(j)) * kRows] =
          linear[static_cast<Eigen::Index>(static_cast<std::size_t>(j) * count + k)];
  std::vector<PathPoint> active;
  std::vector<double> active_lambda;
  for (std::size_t k = 0; k < count; ++k) {
    const auto first =
        lambda.begin() + static_cast<std::ptrdiff_t>(k * static_cast<std::size_t>(m * kRows));
    if (std::all_of(first, first + m * kRows, [](double l) { return l == 0.0; })) continue;
    active.push_back(points_[k]);
    active_lambda.insert(active_lambda.end(), first, first + m * kRows);
  }
  Eigen::VectorXd z(v_.thetas + v_.paths);
  z << theta, c;
  const BoundRowsAt rows = PathRows(flat_, v_, active, reserves_, a_min_)(z, true);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(v_.paths);
  for (const auto& t : rows.jacobian)
    if (t.col() >= v_.thetas)
      g[t.col() - v_.thetas] -= active_lambda[static_cast<std::size_t>(t.row())] * t.value();
  return g;
}

}  // namespace flatsos::planner::detail
