#include "bounds/sequential_lp.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "flatsos/planner/numerics/simplex_lp.hpp"

namespace flatsos::planner::detail {

namespace {
constexpr double kInitialPenalty = 1e4, kMaxPenalty = 1e12;

// The bound rows' Jacobian by rows, built from its triplets in O(nonzeros) whatever their order:
// the step LPs take a few of its rows, and every row's norm and step are needed.
class JacobianByRow {
 public:
  explicit JacobianByRow(const BoundRowsAt& rows) : start_(rows.value.size() + 1, 0) {
    for (const auto& t : rows.jacobian) ++start_[static_cast<std::size_t>(t.row()) + 1];
    for (std::size_t i = 1; i < start_.size(); ++i) start_[i] += start_[i - 1];
    column_.resize(rows.jacobian.size());
    value_.resize(rows.jacobian.size());
    std::vector<int> next(start_.begin(), start_.end() - 1);
    for (const auto& t : rows.jacobian) {
      const auto k = static_cast<std::size_t>(next[static_cast<std::size_t>(t.row())]++);
      column_[k] = t.col();
      value_[k] = t.value();
    }
    l1_.assign(rows.value.size(), 0.0);
    for (std::size_t i = 0; i < l1_.size(); ++i)
      for (int k = start_[i]; k < start_[i + 1]; ++k) l1_[i] += std::abs(value_[static_cast<std::size_t>(k)]);
  }
  double l1(std::size_t row) const { return l1_[row]; }
  double dot(std::size_t row, const Eigen::VectorXd& d) const {
    double sum = 0.0;
    for (int k = start_[row]; k < start_[row + 1]; ++k) sum += value_[static_cast<std::size_t>(k)] * d[column_[static_cast<std::size_t>(k)]];
    return sum;
  }
  void append_row(std::size_t row, int lp_row, std::vector<Eigen::Triplet<double>>& entries) const {
    for (int k = start_[row]; k < start_[row + 1]; ++k)
      entries.emplace_back(lp_row, column_[static_cast<std::size_t>(k)], value_[static_cast<std::size_t>(k)]);
  }

 private:
  std::vector<int> start_, column_;
  std::vector<double> value_, l1_;  // l1_: each row's norm (every iteration's box test asks for it)
};

// The smallest box |d| <= r in which the linearization at theta clears every violated row:
// row v + g.d >= 0 needs r >= -v / |g|_1. A start far from feasibility (a receding-horizon step's
// SLP optimum, 100 N below the activation floors) then takes a Newton step at once instead of
// doubling a small radius for ten iterations.
double linear_reach(const LinearProgram& lp, const BoundRowsAt& rows, const JacobianByRow& jacobian,
                    const Eigen::VectorXd& reserve_norm, const Eigen::VectorXd& theta) {
  double reach = 0.0;
  for (std::size_t i = 0; i < rows.value.size(); ++i)
    if (rows.value[i] < 0.0 && jacobian.l1(i) > 0.0) reach = std::max(reach, -rows.value[i] / jacobian.l1(i));
  for (Eigen::Index r = 0; r < lp.G.rows(); ++r) {
    const double value = lp.G.row(r).dot(theta) - lp.row_lower[r];
    if (value < 0.0 && reserve_norm[r] > 0.0) reach = std::max(reach, -value / reserve_norm[r]);
  }
  return reach;
}

// A row of a step LP, value + g . d >= 0: a bound row (index into the nonlinear rows) or a
// reserve row (index into the linear part's lp.G), with the l1 norm of its g.
struct StepRow {
  bool reserve = false;
  int index = 0;
  double value = 0.0, norm = 0.0;
};

// The rows a step LP starts with: the violated ones (they carry the penalty), the ones active
// in the last LP (not basic there), and the `closest` others that the smallest move reaches.
// At an optimum about as many rows are active as there are free coefficients; the rest of the
// box's 1000-odd rows (the leg's receding-horizon steps) only make the LP slow to load and factor.
template <class StatusOf>
std::vector<char> working_set(const std::vector<StepRow>& candidates, StatusOf status_of, std::size_t closest) {
  std::vector<char> in(candidates.size(), 0);
  std::vector<std::pair<double, std::size_t>> reach;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    const StepRow& c = candidates[k];
    if (c.value < 0.0 || status_of(c) != BasisStatus::Basic) in[k] = 1;
    else reach.emplace_back(c.value / c.norm, k);  // norm > 0: a candidate reaches zero in the box
  }
  if (reach.size() > closest) {
    std::nth_element(reach.begin(), reach.begin() + static_cast<std::ptrdiff_t>(closest), reach.end());
    reach.resize(closest);
  }
  for (const auto& r : reach) in[r.second] = 1;
  return in;
}
}  // namespace

NonlinearRows bound_rows_of(const FlatOutputMap& flat, const std::vector<BoundPoint>& points, const Eigen::VectorXd& a_min,
                            double margin) {
  return [&flat, &points, a_min, margin](const Eigen::VectorXd& x, bool jacobian) {
    return evaluate_rows(flat, points, a_min, x, jacobian, margin);
  };
}

SequentialLpOutcome solve_by_sequential_lp(const SequentialLpLinearPart& linear, const NonlinearRows& nonlinear_rows, Eigen::VectorXd& theta,
                               double& radius, SequentialLpBasis& basis, const SequentialLpSettings& settings, BoundRowsAt* rows_at_theta) {
  SequentialLpOutcome out;
  const LinearProgram& lp = linear.lp;
  const Eigen::Index n = theta.size();
  if (lp.cost.size() != n || lp.G.cols() != n) throw std::logic_error("bounds SLP: the linear part has other variables than theta");
  auto rows_at = [&](const Eigen::VectorXd& x) { return nonlinear_rows(x, true); };
  // The rows at theta, kept in step with it (every return leaves them so).
  BoundRowsAt own;
  BoundRowsAt& rows = rows_at_theta ? *rows_at_theta : own;
  if (!rows_at_theta) rows = rows_at(theta);
  double penalty = kInitialPenalty;
  auto merit = [&](const Eigen::VectorXd& x, const BoundRowsAt& r) {
    return lp.cost.dot(x) + penalty * (r.violation + reserve_violation_N(lp, x));
  };
  double phi = merit(theta, rows);
  const Eigen::VectorXd reserve_norm = lp.G.rows() ? Eigen::VectorXd(lp.G.cwiseAbs().rowwise().sum()) : Eigen::VectorXd();
  JacobianByRow jacobian(rows);
  radius = std::max(radius, linear_reach(lp, rows, jacobian, reserve_norm, theta));
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
  // Every imposed row holds: bound rows to their margin (so that a and n are inside at the
  // point), reserve rows to half the exchange margin.
  auto rows_hold = [&]() {
    const double worst_row = rows.value.empty() ? 0.0 : *std::min_element(rows.value.begin(), rows.value.end());
    const double worst_reserve = lp.G.rows() ? (lp.G * theta - lp.row_lower).minCoeff() : 0.0;
    return worst_row >= -kBoundMargin && worst_reserve >= -0.5 * linear.reserve_margin_N;
  };
  for (; out.iterations < settings.max_iterations; ++out.iterations) {
    // Rows that cannot reach zero inside the box are left out of this LP.
    const Eigen::VectorXd reserve_value = lp.G.rows() ? Eigen::VectorXd(lp.G * theta - lp.row_lower) : Eigen::VectorXd();
    std::vector<StepRow> candidates;
    for (std::size_t i = 0; i < rows.value.size(); ++i)
      if (const double norm = jacobian.l1(i); rows.value[i] - radius * norm < 0.0)
        candidates.push_back({false, static_cast<int>(i), rows.value[i], norm});
    for (Eigen::Index r = 0; r < lp.G.rows(); ++r)
      if (reserve_value[r] - radius * reserve_norm[r] < 0.0)
        candidates.push_back({true, static_cast<int>(r), reserve_value[r], reserve_norm[r]});
    basis.bound_row.resize(rows.value.size(), BasisStatus::Basic);
    basis.bound_slack.resize(rows.value.size(), BasisStatus::AtLower);
    auto status_of = [&](const StepRow& c) -> BasisStatus& {
      if (!c.reserve) return basis.bound_row[static_cast<std::size_t>(c.index)];
      const auto [constraint, point] = reserve_id[static_cast<std::size_t>(c.index)];
      return basis.reserve_row[constraint][point];
    };
    auto slack_of = [&](const StepRow& c) -> BasisStatus& {
      if (!c.reserve) return basis.bound_slack[static_cast<std::size_t>(c.index)];
      const auto [constraint, point] = reserve_id[static_cast<std::size_t>(c.index)];
      return basis.reserve_slack[constraint][point];
    };
    // The step's linearized row at d (its value at theta + g . d).
    auto linear_at = [&](const StepRow& c, const Eigen::VectorXd& d) {
      return c.value + (c.reserve ? lp.G.row(c.index).dot(d) : jacobian.dot(static_cast<std::size_t>(c.index), d));
    };
    const auto closest = static_cast<std::size_t>(settings.closest_rows_per_coefficient * n);
    std::vector<char> in = settings.working_set ? working_set(candidates, status_of, closest) : std::vector<char>(candidates.size(), 1);
    // Variables: d (n), then a slack for each row violated at theta (d = 0 meets the others, so
    // the LP stays feasible with far fewer columns). Each LP starts from the last LP's basis,
    // matched by row identity (bound row or reserve row).
    std::vector<int> lp_row(candidates.size(), -1);
    int slacks = 0;
    double cost_scale = 1.0 / penalty;  // 0: the feasibility LP (the violation alone)
    auto solve_step_lp = [&]() {
      std::vector<double> lp_lower;
      std::vector<Eigen::Triplet<double>> entries;
      std::vector<BasisStatus*> row_status, slack_status;  // where each LP row's and slack's status is kept
      slacks = 0;
      for (std::size_t k = 0; k < candidates.size(); ++k) {
        lp_row[k] = -1;
        if (!in[k]) continue;
        const StepRow& c = candidates[k];
        const int r = static_cast<int>(lp_lower.size());
        lp_row[k] = r;
        lp_lower.push_back(-c.value);
        row_status.push_back(&status_of(c));
        if (c.value < 0.0) {
          entries.emplace_back(r, n + slacks++, 1.0);
          slack_status.push_back(&slack_of(c));
        }
        if (c.reserve) {
          for (Eigen::Index col = 0; col < n; ++col)
            if (lp.G(c.index, col) != 0.0) entries.emplace_back(r, col, lp.G(c.index, col));
        } else {
          jacobian.append_row(static_cast<std::size_t>(c.index), r, entries);
        }
      }
      const Eigen::Index vars = n + slacks, lp_rows = static_cast<Eigen::Index>(lp_lower.size());
      SparseLinearProgram sub;
      sub.cost.resize(vars);
      // The merit divided by the penalty: slacks cost 1 and the step's cost shrinks as the
      // penalty grows (slack costs of 1e11 next to gradients of 1e-6 made Clp call these
      // always-feasible LPs infeasible).
      sub.cost.head(n) = lp.cost * cost_scale;
      sub.cost.tail(slacks).setConstant(1.0);
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
      LinearProgramResult result = solve_linear_program_simplex(sub, start);
      if (result.status != SolveStatus::Solved) {
        // Every step LP is feasible (d = 0 with the violated rows' slacks): a verdict of
        // infeasibility or numerical errors is Clp's, from the start basis (seen on rows whose
        // gradients span 1e-6 to 1e6). Solved again from scratch.
        SimplexBasis cold;
        result = solve_linear_program_simplex(sub, cold);
        start = std::move(cold);
      }
      std::copy_n(start.variables.begin(), n, basis.step.begin());
      for (std::size_t k = 0; k < slack_status.size(); ++k) *slack_status[k] = start.variables[static_cast<std::size_t>(n) + k];
      for (std::size_t k = 0; k < row_status.size(); ++k) *row_status[k] = start.rows[k];
      out.lp_pivots += result.iterations;
      ++out.lp_solves;
      out.lp_rows += lp_rows;
      return result;
    };
    // Rows left out that the step's linearization would violate join, and the LP is solved again
    // from its basis: the set only grows, and the last step is the LP's over every candidate.
    auto solve_over_candidates = [&](LinearProgramResult& lp_step, Eigen::VectorXd& lp_d) {
      for (;;) {
        lp_step = solve_step_lp();
        if (lp_step.status != SolveStatus::Solved) {
          out.failure = "a step LP was not solved (Clp: " + lp_step.solver_status + ")";
          return false;
        }
        lp_d = lp_step.x.head(n);
        bool joined = false;
        for (std::size_t k = 0; k < candidates.size(); ++k)
          if (!in[k] && linear_at(candidates[k], lp_d) < 0.0) in[k] = joined = true;
        if (!joined) return true;
      }
    };
    // The linearized rows' violation at d. The rows left out are >= 0 at 0 and at d in the
    // linearization: they add nothing.
    auto linear_violation = [&](const Eigen::VectorXd& at) {
      double sum = 0.0;
      for (const StepRow& c : candidates) sum += std::max(0.0, -linear_at(c, at));
      return sum;
    };
    double violation_now = 0.0;  // the linearization's at d = 0
    for (const StepRow& c : candidates) violation_now += std::max(0.0, -c.value);
    LinearProgramResult step;
    Eigen::VectorXd d;
    if (!solve_over_candidates(step, d)) return out;
    std::vector<int> step_row = lp_row;  // the step LP's rows (a feasibility LP may follow)
    // Violations at the LP's resolution (the bound rows' margin) are left to the settling below.
    // A step that removes a tenth of the linearized violation removes a tenth of what the
    // violation's own LP can (never more than all of it): the penalty stays, and that LP, which
    // could only confirm it, is not solved (the arm's free path: 182 -> 142 LPs, the same plans).
    double step_violation = linear_violation(d);  // the linearized rows' at d (kept while d is)
    const bool step_steers = violation_now - step_violation >= 0.1 * violation_now;
    if (settings.steering && violation_now > kBoundMargin && !step_steers) {
      // Steering (Byrd, Nocedal and Waltz): the step must remove a tenth of what the
      // violation's own LP can remove in this box, or the penalty rises now, not after the
      // iteration has settled at a penalty too low (each settling cost dozens of LP steps).
      cost_scale = 0.0;
      LinearProgramResult feasibility;
      Eigen::VectorXd d_feasibility;
      if (!solve_over_candidates(feasibility, d_feasibility)) return out;
      const double best = violation_now - linear_violation(d_feasibility);
      // The LP itself leaves violation (its slacks above the margin): what it cannot remove is
      // not below its resolution (Clp holds rows to about 5e-7 of their size).
      const bool lp_keeps_violation = slacks > 0 && feasibility.x.tail(slacks).sum() > kBoundMargin;
      if (lp_keeps_violation && best <= 1e-9 * (1.0 + violation_now)) {
        // No step lowers the linearized violation in this box, so none in any box (it is
        // convex in d): a stationary point of the violation. Inside the bounds to their
        // resolution, or the flat outputs of this basis cannot meet them from here.
        out.converged = true;
        out.rows_violated = !rows_hold();
        return out;
      }
      while (violation_now - step_violation < 0.1 * best && penalty < kMaxPenalty) {
        penalty *= 10.0;
        phi = merit(theta, rows);
        cost_scale = 1.0 / penalty;
        if (!solve_over_candidates(step, d)) return out;
        step_violation = linear_violation(d);
        step_row = lp_row;
      }
      cost_scale = 1.0 / penalty;
    }
    out.row_multipliers.assign(rows.value.size(), 0.0);
    out.linear_row_multipliers = Eigen::VectorXd::Zero(lp.G.rows());
    for (std::size_t k = 0; k < candidates.size(); ++k)
      if (step_row[k] >= 0) {
        const double y = penalty * std::max(0.0, step.row_multipliers[step_row[k]]);
        if (candidates[k].reserve) out.linear_row_multipliers[candidates[k].index] = y;
        else out.row_multipliers[static_cast<std::size_t>(candidates[k].index)] = y;
      }
    const bool lp_paid_violation = slacks > 0 && step.x.tail(slacks).sum() > kBoundMargin;
    // The predicted decrease from the linearized rows at d itself, not from the LP's slacks:
    // those carry the LP's own feasibility tolerance, which the penalty would magnify. The rows
    // left out are >= 0 at 0 and at d in the linearization: they add nothing.
    const double predicted = penalty * (violation_now - step_violation) - lp.cost.dot(d);
    const double step_size = d.size() ? d.cwiseAbs().maxCoeff() : 0.0;
    // Settled: nothing left to gain, or steps far below any meaningful force. Done when every
    // imposed row holds (bound rows to their margin, so that a and n are inside at the point;
    // reserve rows to half the exchange margin); otherwise the violated rows' multipliers exceed
    // the penalty: raise it and go on.
    auto settle = [&]() {
      const bool hold = rows_hold();
      // An LP that left every slack at zero believes its rows met: what remains is below its
      // resolution, a higher price only repeats the same LP, and it is no sign of infeasibility.
      out.rows_violated = !hold && lp_paid_violation;
      if (hold || penalty >= kMaxPenalty || !lp_paid_violation) return true;
      penalty *= 10.0;
      phi = merit(theta, rows);
      return false;
    };
    if (predicted <= settings.relative_decrease * (1.0 + std::abs(phi))) {
      if (settle()) {
        out.converged = true;
        return out;
      }
      continue;
    }
    const Eigen::VectorXd trial = theta + d;
    BoundRowsAt trial_rows = rows_at(trial);
    const double trial_phi = merit(trial, trial_rows);
    const double ratio = (phi - trial_phi) / predicted;
    if (ratio < 0.25) radius = 0.5 * step_size;
    else if (ratio > 0.75 && step_size >= 0.99 * radius) radius *= 2.0;
    const bool accepted = ratio > 0.1;
    if (accepted) {
      theta = trial;
      rows = std::move(trial_rows);
      jacobian = JacobianByRow(rows);
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
  out.failure = "the sequential LP did not converge in " + std::to_string(settings.max_iterations) + " iterations";
  return out;
}

}  // namespace flatsos::planner::detail
