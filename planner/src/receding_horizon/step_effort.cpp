#include "receding_horizon/step_effort.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "bounds/effort_model.hpp"
#include "bounds/sequential_lp.hpp"
#include "numerics/dense_qp.hpp"
#include "receding_horizon/period_bounds.hpp"

namespace flatsos::planner::detail {

namespace {

constexpr int kStepMaxIterations = 30;
constexpr int kStepMaxHalvings = 10;
// Stops once the QP predicts a decrease below this fraction of the effort.
constexpr double kStepRelativeDecrease = 1e-8;
// A trial alpha counts as inside the bounds while every row keeps half its margin (the samples
// then stay strictly inside; bound_rows.hpp).
constexpr double kRowTolerance = 0.5 * kSampleMargin;
// A start may leave its rows by this much in all (row_violation): the last step's optimum, at
// the rows it was pressed against, leaves this step's by 0.02-0.03 on arm26, and the first QP
// steps clear them. Farther out the bounds' sequential LP moves alpha in first.
constexpr double kMaxStartViolation = 1e-1;

// The horizon's grid for the effort: `grid_points` times i T / grid_points, each weighing T /
// grid_points (the horizon's end, where the plan's torques jump to the rest that follows it, is
// left out).
std::vector<BoundPoint> effort_points(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                      const RecedingHorizonOptions& o, RecedingHorizonStep& step, std::vector<double>& weights_s) {
  const int count = o.grid_points;
  const double h = o.horizon_s / count;
  muscle_torques(flat, workspace, o, step, h, count, step.buffers.effort_grid);
  weights_s.assign(static_cast<std::size_t>(count), h);
  return step_points(flat, step, step.buffers.effort_grid, h, count);
}

// How far alpha leaves its rows: the sum of each bound row's excess beyond kRowTolerance below 0
// (activation units), plus the reserve rows' and alpha >= 0's excess over the largest reserve
// bound (0: inside every row).
double row_violation(const RecedingHorizonStep& step, const NonlinearRows* rows, const Eigen::VectorXd& alpha) {
  const double scale = 1.0 + step.bound_N.cwiseAbs().maxCoeff();
  // alpha >= 0 and the reserve rows to rounding: the QP meets them only so.
  double excess = (-alpha.array() - 1e-9 * scale).cwiseMax(0.0).sum() / scale;
  for (Eigen::Index i = 0; i < step.bound_N.size(); ++i)
    excess += std::max(0.0, step.bound_N[i] - step.reserve_rows.row(i).dot(alpha) - 1e-9 * scale) / scale;
  if (rows)
    for (const double r : (*rows)(alpha, false).value) excess += std::max(0.0, -r - kRowTolerance);
  return excess;
}

// The QP's rows J d >= lower: the bound rows linearized at alpha, the reserve rows, alpha + d >= 0.
// A violated bound row asks the step to clear it; one that alpha does not move (rows at t = 0 of
// a plan that starts from the muscles' state) only not to get worse.
void qp_rows(const RecedingHorizonStep& step, const NonlinearRows* rows, const Eigen::VectorXd& alpha, Eigen::MatrixXd& J,
             Eigen::VectorXd& lower) {
  const Eigen::Index p = alpha.size(), reserves = step.reserve_rows.rows();
  BoundRowsAt at;
  if (rows) at = (*rows)(alpha, true);
  const auto bound_rows = static_cast<Eigen::Index>(at.value.size());
  J.setZero(bound_rows + reserves + p, p);
  lower.resize(J.rows());
  place_linearized_bound_rows(at, J, lower);
  J.middleRows(bound_rows, reserves) = step.reserve_rows;
  lower.segment(bound_rows, reserves) = step.bound_N - step.reserve_rows * alpha;
  J.bottomRows(p).setIdentity();
  lower.tail(p) = -alpha;
}

}  // namespace

bool minimize_step_effort(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const RecedingHorizonOptions& o,
                          RecedingHorizonStep& step) {
  step.effort_iterations = 0;
  step.effort_value = o.effort ? std::numeric_limits<double>::quiet_NaN() : 0.0;  // until minimized
  if (step.status != SolveStatus::Solved || !o.effort) return true;
  const Effort& effort = *o.effort;
  const PeriodExcitationBounds& b = o.excitation_bounds;
  std::vector<double> weights_s;
  const std::vector<BoundPoint> points = effort_points(flat, workspace, o, step, weights_s);
  std::vector<BoundPoint> period;
  if (b.enforce) {  // the first period's samples, where sample_period puts them
    muscle_torques(flat, workspace, o, step, b.period_s / (b.samples - 1), b.samples, step.buffers.period.torque_grid);
    period = period_points(flat, b, step);
  }
  const NonlinearRows bound_rows = bound_rows_of(flat, period, activation_minima(flat, 0.0), kSampleMargin);
  const NonlinearRows* rows = b.enforce ? &bound_rows : nullptr;

  // Start from the SLP's alpha or from the previous step's optimum, usually close to this one's:
  // the one nearer the bound rows, then the one that costs less.
  Eigen::VectorXd alpha;
  EffortModel model, trial;
  double violation = kMaxStartViolation;
  for (const Eigen::VectorXd* candidate : {&step.slp.alpha, &step.buffers.effort_alpha}) {
    if (candidate->size() != step.slp.alpha.size()) continue;
    const double v = row_violation(step, rows, *candidate);
    if (!(v <= violation) || !evaluate_effort(flat, effort, points, weights_s, *candidate, false, trial)) continue;
    if (alpha.size() && v == violation && trial.value >= model.value) continue;
    alpha = *candidate, violation = v, model.value = trial.value;
  }
  if (alpha.size() == 0 || !evaluate_effort(flat, effort, points, weights_s, alpha, true, model))
    return false;  // the first period's bounds must move alpha first
  DenseQpWorkspace qp;
  Eigen::MatrixXd J;
  Eigen::VectorXd lower, d, trial_alpha;
  int iterations = 0;
  for (; iterations < kStepMaxIterations; ++iterations) {
    qp_rows(step, rows, alpha, J, lower);
    // Levenberg's shift keeps the model strictly convex where the effort is flat in a direction.
    Eigen::MatrixXd H = model.hessian;
    H.diagonal().array() += 1e-9 * std::max(H.diagonal().maxCoeff(), 1e-12);
    const DenseQpResult r = solve_dense_qp(H, model.gradient, J, lower, qp, d);
    if (!r.solved) break;
    const double predicted = model.gradient.dot(d) + 0.5 * d.dot(model.hessian * d);
    if (violation == 0.0 && !(predicted < -kStepRelativeDecrease * (1e-12 + std::abs(model.value)))) break;
    // Inside the rows, a step must keep them and lower the effort (Armijo); outside, come closer.
    double s = 1.0, trial_violation = 0.0;
    bool accepted = false;
    // The full step, usually accepted, is evaluated with the derivatives the next QP needs.
    int k = 0;
    for (; k < kStepMaxHalvings && !accepted; ++k, s *= 0.5) {
      trial_alpha = alpha + s * d;
      trial_violation = row_violation(step, rows, trial_alpha);
      accepted = (violation == 0.0 ? trial_violation == 0.0 : trial_violation < violation) &&
                 evaluate_effort(flat, effort, points, weights_s, trial_alpha, k == 0, trial) &&
                 (violation > 0.0 || trial.value <= model.value + 1e-4 * s * predicted);
    }
    if (!accepted) break;
    alpha = trial_alpha, violation = trial_violation;
    if (k == 1) std::swap(model, trial);
    else if (!evaluate_effort(flat, effort, points, weights_s, alpha, true, model)) break;  // its value is alpha's still
  }
  if (violation > 0.0) return false;  // could not reach the bounds from here
  step.effort_iterations = iterations + 1;
  step.slp.alpha = alpha;
  step.slp.cost_N = step.buffers.slp.costOf(alpha);
  step.effort_value = model.value;
  step.buffers.effort_alpha = alpha;
  if (!b.enforce) return true;
  // The rows keep every sample inside by half their margin; a sample outside all the same is a
  // failed step, as the bounds' sequential LP would report it.
  if (sampled_at_points(flat, period, step)) return true;
  const bool finite = sample_period(flat, workspace, b, step);
  const SampleExcess excess = finite ? worst_excess(flat, step) : SampleExcess{1.0, 0, 0};
  step.first_period_sampled = finite && excess.value <= 0.0;
  if (!step.first_period_sampled) {
    step.status = SolveStatus::Failed;
    step.message = "the effort's optimum leaves the first period's bounds (excess " + std::to_string(excess.value) + ")";
  }
  return true;
}

}  // namespace flatsos::planner::detail
