#include "sos/bounds_slp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "flatsos/planner/numerics/simplex_lp.hpp"

namespace flatsos::planner::detail {

namespace {
constexpr double kInitialPenalty = 1e4, kMaxPenalty = 1e12;

// The smallest box |d| <= r in which the linearization at theta clears every violated row:
// row v + g.d >= 0 needs r >= -v / |g|_1. A start far from feasibility (a receding-horizon step's
// SLP optimum, 100 N below the activation floors) then takes a Newton step at once instead of
// doubling a small radius for ten iterations.
double linear_reach(const LinearProgram& lp, const BoundRowsAt& rows, const Eigen::VectorXd& theta) {
  std::vector<double> norm(rows.value.size(), 0.0);
  for (const auto& t : rows.jacobian) norm[static_cast<std::size_t>(t.row())] += std::abs(t.value());
  double reach = 0.0;
  for (std::size_t i = 0; i < rows.value.size(); ++i)
    if (rows.value[i] < 0.0 && norm[i] > 0.0) reach = std::max(reach, -rows.value[i] / norm[i]);
  for (Eigen::Index r = 0; r < lp.G.rows(); ++r) {
    const double value = lp.G.row(r).dot(theta) - lp.row_lower[r], row_norm = lp.G.row(r).cwiseAbs().sum();
    if (value < 0.0 && row_norm > 0.0) reach = std::max(reach, -value / row_norm);
  }
  return reach;
}
}  // namespace

NonlinearRows bound_rows_of(const FlatOutputMap& flat, const std::vector<BoundPoint>& points, const Eigen::VectorXd& a_min,
                            double margin) {
  return [&flat, &points, a_min, margin](const Eigen::VectorXd& x, bool jacobian) {
    return evaluate_rows(flat, points, a_min, x, jacobian, margin);
  };
}

SlpOutcome solve_bounds_by_slp(const SlpLinearPart& linear, const NonlinearRows& nonlinear_rows, Eigen::VectorXd& theta,
                               double& radius, SlpBasis& basis, int max_iterations, double relative_decrease) {
  SlpOutcome out;
  const LinearProgram& lp = linear.lp;
  const Eigen::Index n = theta.size();
  if (lp.cost.size() != n || lp.G.cols() != n) throw std::logic_error("bounds SLP: the linear part has other variables than theta");
  auto rows_at = [&](const Eigen::VectorXd& x) { return nonlinear_rows(x, true); };
  BoundRowsAt rows = rows_at(theta);
  if (!rows.defined) {
    out.failure = "the start leaves the muscles' domain at a bound point";
    return out;
  }
  double penalty = kInitialPenalty;
  auto merit = [&](const Eigen::VectorXd& x, const BoundRowsAt& r) {
    return lp.cost.dot(x) + penalty * (r.violation + reserve_violation_N(lp, x));
  };
  double phi = merit(theta, rows);
  radius = std::max(radius, linear_reach(lp, rows, theta));
  basis.step.resize(static_cast<std::size_t>(n), BasisStatus::AtLower);
  // Reserve row r of lp is row k of group c (rows in that order; rounds append rows to groups):
  // their statuses are kept per group and row.
  const std::size_t groups = linear.rows_per_group.size();
  basis.reserve_row.resize(groups);
  basis.reserve_slack.resize(groups);
  std::vector<std::pair<std::size_t, std::size_t>> reserve_id;
  for (std::size_t c = 0; c < groups; ++c) {
    const std::size_t points_c = linear.rows_per_group[c];
    basis.reserve_row[c].resize(points_c, BasisStatus::Basic);
    basis.reserve_slack[c].resize(points_c, BasisStatus::AtLower);
    for (std::size_t k = 0; k < points_c; ++k) reserve_id.emplace_back(c, k);
  }
  if (reserve_id.size() != static_cast<std::size_t>(lp.G.rows()))
    throw std::logic_error("bounds SLP: the reserve rows do not match their groups");
  for (; out.iterations < max_iterations; ++out.iterations) {
    // Rows that cannot reach zero inside the box are left out of this LP.
    std::vector<double> row_norm(rows.value.size(), 0.0);
    for (const auto& t : rows.jacobian) row_norm[static_cast<std::size_t>(t.row())] += std::abs(t.value());
    std::vector<int> bound_rows_in;
    for (std::size_t i = 0; i < rows.value.size(); ++i)
      if (rows.value[i] - radius * row_norm[i] < 0.0) bound_rows_in.push_back(static_cast<int>(i));
    const Eigen::VectorXd reserve_value = lp.G.rows() ? Eigen::VectorXd(lp.G * theta - lp.row_lower) : Eigen::VectorXd();
    std::vector<int> reserve_rows_in;
    for (Eigen::Index r = 0; r < lp.G.rows(); ++r)
      if (reserve_value[r] - radius * lp.G.row(r).cwiseAbs().sum() < 0.0) reserve_rows_in.push_back(static_cast<int>(r));
    // Variables: d (n), then a slack for each row violated at theta (d = 0 meets the others, so
    // the LP stays feasible with far fewer columns). Each LP starts from the last LP's basis,
    // matched by row identity (bound row or reserve row).
    basis.bound_row.resize(rows.value.size(), BasisStatus::Basic);
    basis.bound_slack.resize(rows.value.size(), BasisStatus::AtLower);
    std::vector<double> lp_lower;
    std::vector<Eigen::Triplet<double>> entries;
    std::vector<BasisStatus*> row_status, slack_status;  // where each LP row's and slack's status is kept
    int slacks = 0;
    auto add_row = [&](double lower, BasisStatus& status, BasisStatus& slack) {
      const int r = static_cast<int>(lp_lower.size());
      lp_lower.push_back(lower);
      row_status.push_back(&status);
      if (lower > 0.0) {
        entries.emplace_back(r, n + slacks++, 1.0);
        slack_status.push_back(&slack);
      }
      return r;
    };
    std::vector<int> lp_row_of(rows.value.size(), -1), reserve_lp_row;
    for (int i : bound_rows_in) {
      const auto k = static_cast<std::size_t>(i);
      lp_row_of[k] = add_row(-rows.value[k], basis.bound_row[k], basis.bound_slack[k]);
    }
    for (const auto& t : rows.jacobian)
      if (const int r = lp_row_of[static_cast<std::size_t>(t.row())]; r >= 0) entries.emplace_back(r, t.col(), t.value());
    for (int r : reserve_rows_in) {
      const auto [constraint, point] = reserve_id[static_cast<std::size_t>(r)];
      const int row = add_row(-reserve_value[r], basis.reserve_row[constraint][point], basis.reserve_slack[constraint][point]);
      reserve_lp_row.push_back(row);
      for (Eigen::Index c = 0; c < n; ++c)
        if (lp.G(r, c) != 0.0) entries.emplace_back(row, c, lp.G(r, c));
    }
    const Eigen::Index vars = n + slacks, lp_rows = static_cast<Eigen::Index>(lp_lower.size());
    SparseLinearProgram sub;
    sub.cost.resize(vars);
    sub.cost.head(n) = lp.cost;
    sub.cost.tail(slacks).setConstant(penalty);
    sub.x_lower.resize(vars);
    sub.x_upper.resize(vars);
    for (Eigen::Index i = 0; i < n; ++i) {
      sub.x_lower[i] = std::max(-radius, lp.x_lower[i] - theta[i]);
      sub.x_upper[i] = std::min(radius, lp.x_upper[i] - theta[i]);
    }
    sub.x_lower.tail(slacks).setZero();
    sub.x_upper.tail(slacks).setConstant(1e19);
    sub.row_lower = Eigen::Map<const Eigen::VectorXd>(lp_lower.data(), lp_rows);
    sub.row_upper = Eigen::VectorXd::Constant(lp_rows, 1e19);
    sub.G.resize(lp_rows, vars);
    sub.G.setFromTriplets(entries.begin(), entries.end());
    SimplexBasis start;
    start.variables = basis.step;
    for (BasisStatus* status : slack_status) start.variables.push_back(*status);
    for (BasisStatus* status : row_status) start.rows.push_back(*status);
    const LinearProgramResult step = solve_linear_program_simplex(sub, start);
    std::copy_n(start.variables.begin(), n, basis.step.begin());
    for (std::size_t k = 0; k < slack_status.size(); ++k) *slack_status[k] = start.variables[static_cast<std::size_t>(n) + k];
    for (std::size_t k = 0; k < row_status.size(); ++k) *row_status[k] = start.rows[k];
    out.lp_pivots += step.iterations;
    if (step.status != SolveStatus::Solved) {
      out.failure = "a step LP was not solved (Clp: " + step.solver_status + ")";
      return out;
    }
    out.row_multipliers.assign(rows.value.size(), 0.0);
    for (std::size_t i = 0; i < rows.value.size(); ++i)
      if (lp_row_of[i] >= 0) out.row_multipliers[i] = std::max(0.0, step.row_multipliers[lp_row_of[i]]);
    out.linear_row_multipliers = Eigen::VectorXd::Zero(lp.G.rows());
    for (std::size_t k = 0; k < reserve_rows_in.size(); ++k)
      out.linear_row_multipliers[reserve_rows_in[k]] = std::max(0.0, step.row_multipliers[reserve_lp_row[k]]);
    const Eigen::VectorXd d = step.x.head(n);
    const bool lp_paid_violation = slacks > 0 && step.x.tail(slacks).sum() > kBoundMargin;
    // The predicted decrease from the linearized rows at d itself, not from the LP's slacks:
    // those carry the LP's own feasibility tolerance, which the penalty would magnify. The rows
    // left out are >= 0 at 0 and at d in the linearization: they add nothing.
    Eigen::VectorXd linear_at_d = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(rows.value.size()));
    for (const auto& t : rows.jacobian) linear_at_d[t.row()] += t.value() * d[t.col()];
    double violation_now = 0.0, violation_at_d = 0.0;
    for (int i : bound_rows_in) {
      const double v = rows.value[static_cast<std::size_t>(i)];
      violation_now += std::max(0.0, -v);
      violation_at_d += std::max(0.0, -(v + linear_at_d[i]));
    }
    for (int r : reserve_rows_in) {
      violation_now += std::max(0.0, -reserve_value[r]);
      violation_at_d += std::max(0.0, -(reserve_value[r] + lp.G.row(r).dot(d)));
    }
    const double predicted = penalty * (violation_now - violation_at_d) - lp.cost.dot(d);
    const double step_size = d.size() ? d.cwiseAbs().maxCoeff() : 0.0;
    // Settled: nothing left to gain, or steps far below any meaningful force. Done when every
    // imposed row holds (bound rows to their margin, so that a and n are inside at the point;
    // reserve rows to half the exchange margin); otherwise the violated rows' multipliers exceed
    // the penalty: raise it and go on.
    auto settle = [&]() {
      const double worst_row = *std::min_element(rows.value.begin(), rows.value.end());
      const double worst_reserve = lp.G.rows() ? (lp.G * theta - lp.row_lower).minCoeff() : 0.0;
      const bool rows_hold = worst_row >= -kBoundMargin && worst_reserve >= -0.5 * linear.reserve_margin_N;
      // An LP that left every slack at zero believes its rows met: what remains is below its
      // resolution, a higher price only repeats the same LP, and it is no sign of infeasibility.
      out.rows_violated = !rows_hold && lp_paid_violation;
      if (rows_hold || penalty >= kMaxPenalty || !lp_paid_violation) return true;
      penalty *= 10.0;
      phi = merit(theta, rows);
      return false;
    };
    if (predicted <= relative_decrease * (1.0 + std::abs(phi))) {
      if (settle()) {
        out.converged = true;
        return out;
      }
      continue;
    }
    const Eigen::VectorXd trial = theta + d;
    BoundRowsAt trial_rows = rows_at(trial);
    const double trial_phi = trial_rows.defined ? merit(trial, trial_rows) : std::numeric_limits<double>::infinity();
    const double ratio = (phi - trial_phi) / predicted;
    if (ratio < 0.25) radius = 0.5 * step_size;
    else if (ratio > 0.75 && step_size >= 0.99 * radius) radius *= 2.0;
    const bool accepted = ratio > 0.1;
    if (accepted) {
      theta = trial;
      rows = std::move(trial_rows);
      phi = trial_phi;
      // Near the solution steps shrink quadratically: a box a little larger than the last step
      // keeps only the rows that can become active in the next LP (far smaller LPs).
      radius = std::min(radius, std::max(10.0 * step_size, 1e-6 * (1.0 + theta.cwiseAbs().maxCoeff())));
    }
    const double scale = 1.0 + theta.cwiseAbs().maxCoeff();
    if ((accepted && step_size <= 1e-7 * scale) || radius < 1e-10 * scale) {
      if (settle()) {
        out.converged = true;
        return out;
      }
      radius = std::max(radius, 1e-6 * scale);
    }
  }
  out.failure = "the sequential LP did not converge in " + std::to_string(max_iterations) + " iterations";
  return out;
}

}  // namespace flatsos::planner::detail
