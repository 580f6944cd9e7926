#include "bounds/sequential_lp.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "flatsos/planner/numerics/simplex_lp.hpp"

namespace flatsos::planner::detail {

namespace {
constexpr double kInitialPenalty = 1e4, kMaxPenalty = 1e12;

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

namespace {

// One call of solve_by_sequential_lp: the iterate and its rows, the penalty and merit, the trust
// radius and the LP basis, and per iteration the step LP's candidate rows.
class SequentialLp {
 public:
  SequentialLp(const SequentialLpLinearPart& linear, const NonlinearRows& nonlinear_rows, Eigen::VectorXd& theta,
               double& radius, SequentialLpBasis& basis, const SequentialLpSettings& settings, BoundRowsAt* rows_at_theta)
      : linear_(linear), lp_(linear.lp), nonlinear_rows_(nonlinear_rows), theta_(theta), radius_(radius), basis_(basis),
        settings_(settings), n_(theta.size()), rows_(rows_at_theta ? *rows_at_theta : own_rows_) {
    if (lp_.cost.size() != n_ || lp_.G.cols() != n_)
      throw std::logic_error("bounds sequential LP: the linear part has other variables than theta");
    if (!rows_at_theta) rows_ = rowsAt(theta_);
    phi_ = merit(theta_, rows_);
    if (lp_.G.rows()) reserve_norm_ = lp_.G.cwiseAbs().rowwise().sum();
    jacobian_ = JacobianByRow(rows_);
    radius_ = std::max(radius_, linear_reach(lp_, rows_, jacobian_, reserve_norm_, theta_));
    identifyReserveRows();
  }

  SequentialLpOutcome run() {
    for (; out_.iterations < settings_.max_iterations; ++out_.iterations) {
      collectCandidates();
      LinearProgramResult step;
      Eigen::VectorXd d;
      if (!solveOverCandidates(step, d)) return out_;
      std::vector<int> step_row = lp_row_;  // the step LP's rows (a feasibility LP may follow)
      double step_violation = linearViolation(d);  // the linearized rows' at d (kept while d is)
      if (steer(step, d, step_violation, step_row) == Steering::Stop) return out_;
      recordMultipliers(step, step_row);
      const bool lp_paid_violation = slacks_ > 0 && step.x.tail(slacks_).sum() > kBoundMargin;
      // The predicted decrease from the linearized rows at d itself, not from the LP's slacks:
      // those carry the LP's own feasibility tolerance, which the penalty would magnify.
      const double predicted = penalty_ * (violation_now_ - step_violation) - lp_.cost.dot(d);
      if (predicted <= settings_.relative_decrease * (1.0 + std::abs(phi_))) {
        if (settle(lp_paid_violation)) return converged();
        continue;
      }
      if (trustRegionStep(d, predicted, lp_paid_violation)) return converged();
    }
    out_.failure = "the sequential LP did not converge in " + std::to_string(settings_.max_iterations) + " iterations";
    return out_;
  }

 private:
  enum class Steering { Go, Stop };

  BoundRowsAt rowsAt(const Eigen::VectorXd& x) const { return nonlinear_rows_(x, true); }
  double merit(const Eigen::VectorXd& x, const BoundRowsAt& r) const {
    return lp_.cost.dot(x) + penalty_ * (r.violation + reserve_violation_N(lp_, x));
  }
  SequentialLpOutcome converged() {
    out_.converged = true;
    return out_;
  }

  // Reserve row r of lp is row k of group c (rows in that order; rounds append rows to groups):
  // their statuses are kept per group and row.
  void identifyReserveRows() {
    basis_.step.resize(static_cast<std::size_t>(n_), BasisStatus::AtLower);
    const std::size_t groups = linear_.rows_per_group.size();
    basis_.reserve_row.resize(groups);
    basis_.reserve_slack.resize(groups);
    for (std::size_t c = 0; c < groups; ++c) {
      const std::size_t points_c = linear_.rows_per_group[c];
      basis_.reserve_row[c].resize(points_c, BasisStatus::Basic);
      basis_.reserve_slack[c].resize(points_c, BasisStatus::AtLower);
      for (std::size_t k = 0; k < points_c; ++k) reserve_id_.emplace_back(c, k);
    }
    if (reserve_id_.size() != static_cast<std::size_t>(lp_.G.rows()))
      throw std::logic_error("bounds sequential LP: the reserve rows do not match their groups");
  }

  // Every imposed row holds: bound rows to their margin (so that a and n are inside at the
  // point), reserve rows to half the exchange margin.
  bool rowsHold() const {
    const double worst_row = rows_.value.empty() ? 0.0 : *std::min_element(rows_.value.begin(), rows_.value.end());
    const double worst_reserve = lp_.G.rows() ? (lp_.G * theta_ - lp_.row_lower).minCoeff() : 0.0;
    return worst_row >= -kBoundMargin && worst_reserve >= -0.5 * linear_.reserve_margin_N;
  }

  // The rows that can reach zero inside the box (the others are left out of this iteration's
  // LPs), the working set the step LP starts from, and the linearized violation at d = 0.
  void collectCandidates() {
    const Eigen::VectorXd reserve_value = lp_.G.rows() ? Eigen::VectorXd(lp_.G * theta_ - lp_.row_lower) : Eigen::VectorXd();
    candidates_.clear();
    for (std::size_t i = 0; i < rows_.value.size(); ++i)
      if (const double norm = jacobian_.l1(i); rows_.value[i] - radius_ * norm < 0.0)
        candidates_.push_back({false, static_cast<int>(i), rows_.value[i], norm});
    for (Eigen::Index r = 0; r < lp_.G.rows(); ++r)
      if (reserve_value[r] - radius_ * reserve_norm_[r] < 0.0)
        candidates_.push_back({true, static_cast<int>(r), reserve_value[r], reserve_norm_[r]});
    basis_.bound_row.resize(rows_.value.size(), BasisStatus::Basic);
    basis_.bound_slack.resize(rows_.value.size(), BasisStatus::AtLower);
    const auto closest = static_cast<std::size_t>(settings_.closest_rows_per_coefficient * n_);
    in_ = settings_.working_set ? working_set(candidates_, [this](const StepRow& c) { return statusOf(c); }, closest)
                                : std::vector<char>(candidates_.size(), 1);
    lp_row_.assign(candidates_.size(), -1);
    cost_scale_ = 1.0 / penalty_;
    violation_now_ = 0.0;
    for (const StepRow& c : candidates_) violation_now_ += std::max(0.0, -c.value);
  }

  BasisStatus& statusOf(const StepRow& c) {
    if (!c.reserve) return basis_.bound_row[static_cast<std::size_t>(c.index)];
    const auto [constraint, point] = reserve_id_[static_cast<std::size_t>(c.index)];
    return basis_.reserve_row[constraint][point];
  }
  BasisStatus& slackOf(const StepRow& c) {
    if (!c.reserve) return basis_.bound_slack[static_cast<std::size_t>(c.index)];
    const auto [constraint, point] = reserve_id_[static_cast<std::size_t>(c.index)];
    return basis_.reserve_slack[constraint][point];
  }
  // The step's linearized row at d (its value at theta + g . d).
  double linearAt(const StepRow& c, const Eigen::VectorXd& d) const {
    return c.value + (c.reserve ? lp_.G.row(c.index).dot(d) : jacobian_.dot(static_cast<std::size_t>(c.index), d));
  }
  // The linearized rows' violation at d. The rows left out are >= 0 at 0 and at d in the
  // linearization: they add nothing.
  double linearViolation(const Eigen::VectorXd& at) const {
    double sum = 0.0;
    for (const StepRow& c : candidates_) sum += std::max(0.0, -linearAt(c, at));
    return sum;
  }

  // The step LP over the working set: variables d (n), then a slack for each row violated at
  // theta (d = 0 meets the others, so the LP stays feasible with far fewer columns). It starts
  // from the last LP's basis, matched by row identity (bound row or reserve row).
  LinearProgramResult solveStepLp() {
    std::vector<double> lp_lower;
    std::vector<Eigen::Triplet<double>> entries;
    std::vector<BasisStatus*> row_status, slack_status;  // where each LP row's and slack's status is kept
    slacks_ = 0;
    for (std::size_t k = 0; k < candidates_.size(); ++k) {
      lp_row_[k] = -1;
      if (!in_[k]) continue;
      const StepRow& c = candidates_[k];
      const int r = static_cast<int>(lp_lower.size());
      lp_row_[k] = r;
      lp_lower.push_back(-c.value);
      row_status.push_back(&statusOf(c));
      if (c.value < 0.0) {
        entries.emplace_back(r, n_ + slacks_++, 1.0);
        slack_status.push_back(&slackOf(c));
      }
      if (c.reserve) {
        for (Eigen::Index col = 0; col < n_; ++col)
          if (lp_.G(c.index, col) != 0.0) entries.emplace_back(r, col, lp_.G(c.index, col));
      } else {
        jacobian_.append_row(static_cast<std::size_t>(c.index), r, entries);
      }
    }
    const SparseLinearProgram sub = stepProgram(lp_lower, entries);
    SimplexBasis start;
    start.variables = basis_.step;
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
    std::copy_n(start.variables.begin(), n_, basis_.step.begin());
    for (std::size_t k = 0; k < slack_status.size(); ++k) *slack_status[k] = start.variables[static_cast<std::size_t>(n_) + k];
    for (std::size_t k = 0; k < row_status.size(); ++k) *row_status[k] = start.rows[k];
    out_.lp_pivots += result.iterations;
    ++out_.lp_solves;
    out_.lp_rows += static_cast<long>(lp_lower.size());
    return result;
  }

  SparseLinearProgram stepProgram(const std::vector<double>& lp_lower,
                                  const std::vector<Eigen::Triplet<double>>& entries) const {
    const Eigen::Index vars = n_ + slacks_, lp_rows = static_cast<Eigen::Index>(lp_lower.size());
    SparseLinearProgram sub;
    sub.cost.resize(vars);
    // The merit divided by the penalty: slacks cost 1 and the step's cost shrinks as the
    // penalty grows (slack costs of 1e11 next to gradients of 1e-6 made Clp call these
    // always-feasible LPs infeasible).
    sub.cost.head(n_) = lp_.cost * cost_scale_;
    sub.cost.tail(slacks_).setConstant(1.0);
    sub.x_lower.resize(vars);
    sub.x_upper.resize(vars);
    for (Eigen::Index i = 0; i < n_; ++i) {
      sub.x_lower[i] = std::max(-radius_, lp_.x_lower[i] - theta_[i]);
      sub.x_upper[i] = std::min(radius_, lp_.x_upper[i] - theta_[i]);
    }
    sub.x_lower.tail(slacks_).setZero();
    sub.x_upper.tail(slacks_).setConstant(1e19);
    sub.row_lower = Eigen::Map<const Eigen::VectorXd>(lp_lower.data(), lp_rows);
    sub.row_upper = Eigen::VectorXd::Constant(lp_rows, 1e19);
    sub.G.resize(lp_rows, vars);
    sub.G.setFromTriplets(entries.begin(), entries.end());
    return sub;
  }

  // Rows left out that the step's linearization would violate join, and the LP is solved again
  // from its basis: the set only grows, and the last step is the LP's over every candidate.
  bool solveOverCandidates(LinearProgramResult& lp_step, Eigen::VectorXd& lp_d) {
    for (;;) {
      lp_step = solveStepLp();
      if (lp_step.status != SolveStatus::Solved) {
        out_.failure = "a step LP was not solved (Clp: " + lp_step.solver_status + ")";
        return false;
      }
      lp_d = lp_step.x.head(n_);
      bool joined = false;
      for (std::size_t k = 0; k < candidates_.size(); ++k)
        if (!in_[k] && linearAt(candidates_[k], lp_d) < 0.0) in_[k] = joined = true;
      if (!joined) return true;
    }
  }

  // Steering (Byrd, Nocedal and Waltz): the step must remove a tenth of what the violation's own
  // LP can remove in this box, or the penalty rises now, not after the iteration has settled at a
  // penalty too low (each settling cost dozens of LP steps). A step that already removes a tenth
  // of the linearized violation removes a tenth of what that LP can (never more than all of it):
  // the penalty stays, and that LP is not solved. Violations at the LP's resolution (the bound
  // rows' margin) are left to settle(). Stop: converged at a stationary violation, or failed.
  Steering steer(LinearProgramResult& step, Eigen::VectorXd& d, double& step_violation, std::vector<int>& step_row) {
    const bool step_steers = violation_now_ - step_violation >= 0.1 * violation_now_;
    if (!settings_.steering || violation_now_ <= kBoundMargin || step_steers) return Steering::Go;
    cost_scale_ = 0.0;  // the feasibility LP: the violation alone
    LinearProgramResult feasibility;
    Eigen::VectorXd d_feasibility;
    if (!solveOverCandidates(feasibility, d_feasibility)) return Steering::Stop;
    const double best = violation_now_ - linearViolation(d_feasibility);
    // The LP itself leaves violation (its slacks above the margin): what it cannot remove is
    // not below its resolution (Clp holds rows to about 5e-7 of their size).
    const bool lp_keeps_violation = slacks_ > 0 && feasibility.x.tail(slacks_).sum() > kBoundMargin;
    if (lp_keeps_violation && best <= 1e-9 * (1.0 + violation_now_)) {
      // No step lowers the linearized violation in this box, so none in any box (it is convex
      // in d): a stationary point of the violation. Inside the bounds to their resolution, or
      // the flat outputs of this basis cannot meet them from here.
      out_.rows_violated = !rowsHold();
      converged();
      return Steering::Stop;
    }
    while (violation_now_ - step_violation < 0.1 * best && penalty_ < kMaxPenalty) {
      penalty_ *= 10.0;
      phi_ = merit(theta_, rows_);
      cost_scale_ = 1.0 / penalty_;
      if (!solveOverCandidates(step, d)) return Steering::Stop;
      step_violation = linearViolation(d);
      step_row = lp_row_;
    }
    cost_scale_ = 1.0 / penalty_;
    return Steering::Go;
  }

  void recordMultipliers(const LinearProgramResult& step, const std::vector<int>& step_row) {
    out_.row_multipliers.assign(rows_.value.size(), 0.0);
    out_.linear_row_multipliers = Eigen::VectorXd::Zero(lp_.G.rows());
    for (std::size_t k = 0; k < candidates_.size(); ++k)
      if (step_row[k] >= 0) {
        const double y = penalty_ * std::max(0.0, step.row_multipliers[step_row[k]]);
        if (candidates_[k].reserve) out_.linear_row_multipliers[candidates_[k].index] = y;
        else out_.row_multipliers[static_cast<std::size_t>(candidates_[k].index)] = y;
      }
  }

  // Settled: nothing left to gain, or steps far below any meaningful force. Done (true) when every
  // imposed row holds; otherwise the violated rows' multipliers exceed the penalty: raise it.
  bool settle(bool lp_paid_violation) {
    const bool hold = rowsHold();
    // An LP that left every slack at zero believes its rows met: what remains is below its
    // resolution, a higher price only repeats the same LP, and it is no sign of infeasibility.
    out_.rows_violated = !hold && lp_paid_violation;
    if (hold || penalty_ >= kMaxPenalty || !lp_paid_violation) return true;
    penalty_ *= 10.0;
    phi_ = merit(theta_, rows_);
    return false;
  }

  // The trust region's test of theta + d by the ratio of actual to predicted merit decrease;
  // true when the iteration has converged.
  bool trustRegionStep(const Eigen::VectorXd& d, double predicted, bool lp_paid_violation) {
    double step_size = d.size() ? d.cwiseAbs().maxCoeff() : 0.0;
    Eigen::VectorXd trial = theta_ + d;
    BoundRowsAt trial_rows = rowsAt(trial);
    double trial_phi = merit(trial, trial_rows);
    const double ratio = (phi_ - trial_phi) / predicted;
    if (ratio < 0.25) radius_ = 0.5 * step_size;
    else if (ratio > 0.75 && step_size >= 0.99 * radius_) radius_ *= 2.0;
    bool accepted = ratio > 0.1;
    if (!accepted && settings_.back_off && backOff(d, trial, trial_rows, trial_phi)) {
      accepted = true;
      step_size = (trial - theta_).cwiseAbs().maxCoeff();
      radius_ = step_size;
    }
    if (accepted) {
      theta_ = trial;
      rows_ = std::move(trial_rows);
      jacobian_ = JacobianByRow(rows_);
      phi_ = trial_phi;
      // Near the solution steps shrink quadratically: a box a little larger than the last step
      // keeps only the rows that can become active in the next LP (far smaller LPs).
      radius_ = std::min(radius_, std::max(10.0 * step_size, 1e-6 * (1.0 + theta_.cwiseAbs().maxCoeff())));
    }
    const double scale = 1.0 + theta_.cwiseAbs().maxCoeff();
    if ((accepted && step_size <= 1e-7 * scale) || radius_ < 1e-10 * scale) {
      if (settle(lp_paid_violation)) return true;
      radius_ = std::max(radius_, 1e-6 * scale);
    }
    return false;
  }

  // A step the rows rejected because rows that held at theta break along it (curving down
  // where the LP saw them straight): the cost falls along d until the first of them reaches
  // zero, at the fraction t of d where each one's quadratic through its value, slope and value
  // at theta + d does. That shorter step into trial (with its rows and merit) when the merit
  // accepts it. Halving the box instead approaches such a row by halves, an LP step rejected at
  // each halving.
  bool backOff(const Eigen::VectorXd& d, Eigen::VectorXd& trial, BoundRowsAt& trial_rows, double& trial_phi) {
    double t = 1.0;
    for (const StepRow& c : candidates_) {
      if (c.reserve || c.value < 0.0) continue;
      const auto i = static_cast<std::size_t>(c.index);
      const double at_end = trial_rows.value[i];
      if (at_end >= -kBoundMargin) continue;
      const double slope = jacobian_.dot(i, d), curve = at_end - c.value - slope;  // v(s) = value + slope s + curve s^2
      if (curve >= 0.0) continue;  // not what broke it
      const double root = (-slope - std::sqrt(slope * slope - 4.0 * curve * c.value)) / (2.0 * curve);
      t = std::min(t, root);
    }
    if (!(t > 1e-3 && t < 1.0)) return false;
    const Eigen::VectorXd shorter = t * d;
    const double predicted = penalty_ * (violation_now_ - linearViolation(shorter)) - lp_.cost.dot(shorter);
    if (!(predicted > 0.0)) return false;
    Eigen::VectorXd x = theta_ + shorter;
    BoundRowsAt rows = rowsAt(x);
    const double phi = merit(x, rows);
    if ((phi_ - phi) / predicted <= 0.1) return false;
    trial = std::move(x);
    trial_rows = std::move(rows);
    trial_phi = phi;
    return true;
  }

  const SequentialLpLinearPart& linear_;
  const LinearProgram& lp_;
  const NonlinearRows& nonlinear_rows_;
  Eigen::VectorXd& theta_;
  double& radius_;
  SequentialLpBasis& basis_;
  const SequentialLpSettings& settings_;
  const Eigen::Index n_;
  BoundRowsAt own_rows_;
  BoundRowsAt& rows_;  // the rows at theta, kept in step with it (every return leaves them so)
  double penalty_ = kInitialPenalty, phi_ = 0.0;
  Eigen::VectorXd reserve_norm_;
  JacobianByRow jacobian_;
  std::vector<std::pair<std::size_t, std::size_t>> reserve_id_;
  SequentialLpOutcome out_;
  // This iteration's step LPs.
  std::vector<StepRow> candidates_;
  std::vector<char> in_;
  std::vector<int> lp_row_;
  int slacks_ = 0;
  double cost_scale_ = 1.0;  // 0: the feasibility LP (the violation alone)
  double violation_now_ = 0.0;  // the linearization's at d = 0
};

}  // namespace

SequentialLpOutcome solve_by_sequential_lp(const SequentialLpLinearPart& linear, const NonlinearRows& nonlinear_rows,
                                           Eigen::VectorXd& theta, double& radius, SequentialLpBasis& basis,
                                           const SequentialLpSettings& settings, BoundRowsAt* rows_at_theta) {
  return SequentialLp(linear, nonlinear_rows, theta, radius, basis, settings, rows_at_theta).run();
}

}  // namespace flatsos::planner::detail
