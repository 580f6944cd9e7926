#include "bounds/effort_sqp.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace flatsos::planner::detail {

namespace {
constexpr int kMaxHalvings = 30;
// Stops once the QP predicts a decrease below this fraction of the effort.
constexpr double kRelativeDecrease = 1e-10;
// A trial theta counts as inside a bound row while the row keeps half its margin.
constexpr double kBoundRowTolerance = 0.5 * kBoundMargin;
}  // namespace

bool EffortSqp::start(const Eigen::VectorXd& theta) {
  return evaluate_effort(p_.flat, p_.effort, p_.effort_points, p_.weights_s, theta, true, model_,
                         true);
}

// How far theta leaves the rows: linear rows in their unit over the largest bound, bound rows in
// activation units, each beyond its tolerance (0: inside every row). A row no coefficient moves
// does not count (qpRows).
double EffortSqp::violation(const Eigen::VectorXd& theta) const {
  const LinearProgram& lp = p_.linear;
  double v = 0.0;
  if (lp.G.rows()) {
    const double scale = 1.0 + lp.row_lower.cwiseAbs().maxCoeff();
    const Eigen::VectorXd short_N = lp.row_lower - lp.G * theta;
    for (Eigen::Index r = 0; r < short_N.size(); ++r)
      if (short_N[r] > p_.linear_slack && lp.G.row(r).cwiseAbs().maxCoeff() > 1e-12)
        v += (short_N[r] - p_.linear_slack) / scale;
  }
  if (!p_.bound_points.empty())
    for (const double r : evaluate_rows(p_.flat, p_.bound_points, p_.a_min, theta, false).value)
      v += std::max(0.0, -r - kBoundRowTolerance);
  return v;
}

namespace {
// The largest |entry| of a row: 0 for a row no coefficient moves.
double row_reach(const SparseRows& J, Eigen::Index row) {
  double largest = 0.0;
  for (SparseRows::InnerIterator it(J, row); it; ++it) largest = std::max(largest, std::abs(it.value()));
  return largest;
}
}  // namespace

// The QP's rows J d >= lower, stored sparse (each touches a few dozen of theta's coefficients):
// the bound rows linearized at theta (a violated one asked to clear, one theta does not move only
// not to get worse), the linear rows, the box.
void EffortSqp::qpRows(const Eigen::VectorXd& theta, SparseRows& J, Eigen::VectorXd& lower) {
  const LinearProgram& lp = p_.linear;
  const Eigen::Index n = theta.size(), linear = lp.G.rows();
  BoundRowsAt& at = rows_at_theta_;
  at = BoundRowsAt{};
  if (!p_.bound_points.empty()) at = evaluate_rows(p_.flat, p_.bound_points, p_.a_min, theta, true);
  const auto bound_rows = static_cast<Eigen::Index>(at.value.size());
  triplets_.assign(at.jacobian.begin(), at.jacobian.end());
  for (const Eigen::Triplet<double>& e : linear_entries_)
    triplets_.emplace_back(static_cast<int>(bound_rows) + e.row(), e.col(), e.value());
  for (Eigen::Index c = 0; c < n; ++c) {
    triplets_.emplace_back(static_cast<int>(bound_rows + linear + c), static_cast<int>(c), 1.0);
    triplets_.emplace_back(static_cast<int>(bound_rows + linear + n + c), static_cast<int>(c), -1.0);
  }
  J.resize(bound_rows + linear + 2 * n, n);
  J.setFromTriplets(triplets_.begin(), triplets_.end());  // repeated entries add up
  lower.resize(J.rows());
  for (Eigen::Index r = 0; r < bound_rows; ++r) lower[r] = -at.value[static_cast<std::size_t>(r)];
  lower.segment(bound_rows, linear) = lp.row_lower - lp.G * theta;
  // A row no coefficient moves (a bound row at t = 0, a reserve there: fixed by the muscles'
  // state) only must not get worse: its margin may be out of reach.
  for (Eigen::Index r = 0; r < bound_rows + linear; ++r)
    if (row_reach(J, r) <= 1e-12) lower[r] = std::min(lower[r], 0.0);
  lower.segment(bound_rows + linear, n) = lp.x_lower - theta;
  lower.tail(n) = theta - lp.x_upper;
}

bool EffortSqp::descend(Eigen::VectorXd& theta, int& steps, int max_steps) {
  double current = violation(theta);
  SparseRows J;
  Eigen::MatrixXd H;
  Eigen::VectorXd lower, d, multipliers;
  const Eigen::MatrixXd& G = p_.linear.G;
  linear_entries_.clear();
  for (Eigen::Index c = 0; c < G.cols(); ++c)  // column by column: G is column-major
    for (Eigen::Index r = 0; r < G.rows(); ++r)
      if (G(r, c) != 0.0) linear_entries_.emplace_back(static_cast<int>(r), static_cast<int>(c), G(r, c));
  while (steps < max_steps) {
    qpRows(theta, J, lower);
    std::vector<int> hint = qpHint(theta.size());
    // Levenberg's shift keeps the model strictly convex where the effort is flat in a direction.
    H = model_.hessian;
    H.diagonal().array() += 1e-9 * std::max(H.diagonal().maxCoeff(), 1e-12);
    const DenseQpResult r =
        solve_dense_qp(H, model_.gradient, J, lower, qp_, d, &multipliers, 1e-10, &hint);
    qp_row_changes_ += r.iterations;
    if (!r.solved) return fail("the effort's QP was not solved: " + r.failure);
    keepActive(qp_.active, theta.size());
    hint = qp_.active;  // the second-order correction's QP starts from this one's rows
    ++steps;
    keepMultipliers(multipliers);
    if (current == 0.0 &&
        !(predictedDecrease(d) < -kRelativeDecrease * (1e-12 + std::abs(model_.value))))
      return true;
    // A full step inside the rows' linearization that leaves the curved rows: first the same QP
    // with the rows' curvature along it taken in (a second-order correction, Nocedal and
    // Wright 2006, section 18.3), then shorter steps.
    bool accepted = false;
    Eigen::VectorXd corrected = d;
    if (current == 0.0 && violation(theta + d) > 0.0 &&
        correctedStep(theta, H, J, lower, corrected, hint))
      accepted = lineSearch(corrected, theta, current);
    if (!accepted) accepted = lineSearch(d, theta, current);
    if (!accepted) {
      if (current == 0.0) return true;  // no decrease along the QP's step: as low as the model sees
      return fail(
          "the effort's sequential QP could not return inside the reserves and bounds (violation " +
          std::to_string(current) + ")");
    }
    if (!evaluate_effort(p_.flat, p_.effort, p_.effort_points, p_.weights_s, theta, true, model_,
                         true))
      return fail("the effort could not be differentiated at an accepted step");
  }
  return fail("the effort's sequential QP did not converge in " + std::to_string(max_steps) +
              " steps");
}

double EffortSqp::predictedDecrease(const Eigen::VectorXd& d) const {
  return model_.gradient.dot(d) + 0.5 * d.dot(model_.hessian * d);
}

// Halvings of d: inside the rows a step must keep them and lower the effort (Armijo); outside,
// come closer. On success theta and `current` move.
bool EffortSqp::lineSearch(const Eigen::VectorXd& d, Eigen::VectorXd& theta, double& current) {
  const double predicted = predictedDecrease(d);
  EffortModel trial;
  double s = 1.0;
  for (int k = 0; k < kMaxHalvings; ++k, s *= 0.5) {
    const Eigen::VectorXd trial_theta = theta + s * d;
    const double trial_violation = violation(trial_theta);
    if ((current == 0.0 ? trial_violation == 0.0 : trial_violation < current) &&
        evaluate_effort(p_.flat, p_.effort, p_.effort_points, p_.weights_s, trial_theta, false,
                        trial, true) &&
        (current > 0.0 || trial.value <= model_.value + 1e-4 * s * predicted)) {
      theta = trial_theta, current = trial_violation;
      return true;
    }
  }
  return false;
}

// d solved again with each bound row's lower bound moved by how far the row at theta + d differs
// from its linearization. False when there are no bound rows or the QP fails.
bool EffortSqp::correctedStep(const Eigen::VectorXd& theta, const Eigen::MatrixXd& H, const SparseRows& J,
                              const Eigen::VectorXd& lower, Eigen::VectorXd& d, std::vector<int>& hint) {
  const std::vector<double>& before = rows_at_theta_.value;
  if (before.empty()) return false;
  const std::vector<double> after =
      evaluate_rows(p_.flat, p_.bound_points, p_.a_min, theta + d, false).value;
  Eigen::VectorXd corrected = lower;
  for (std::size_t i = 0; i < before.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    if (row_reach(J, row) > 1e-12) corrected[row] -= after[i] - before[i] - (J.row(row) * d).value();
  }
  Eigen::VectorXd step;
  const DenseQpResult r = solve_dense_qp(H, model_.gradient, J, corrected, qp_, step, nullptr, 1e-10, &hint);
  qp_row_changes_ += r.iterations;
  if (!r.solved) return false;
  keepActive(qp_.active, theta.size());
  d = step;
  return true;
}

std::vector<int> EffortSqp::qpHint(Eigen::Index n) const {
  const auto bound = static_cast<int>(rows_at_theta_.value.size()), linear = static_cast<int>(p_.linear.G.rows());
  std::vector<int> hint;
  for (const int r : active_.bound)
    if (r < bound) hint.push_back(r);
  for (const int r : active_.linear)
    if (r < linear) hint.push_back(bound + r);
  for (const int r : active_.box)
    if (r < 2 * n) hint.push_back(bound + linear + r);
  return hint;
}

void EffortSqp::keepActive(const std::vector<int>& rows, Eigen::Index n) {
  const auto bound = static_cast<int>(rows_at_theta_.value.size()), linear = static_cast<int>(p_.linear.G.rows());
  active_ = EffortSqpActiveRows{};
  for (const int r : rows) {
    if (r < bound) active_.bound.push_back(r);
    else if (r < bound + linear) active_.linear.push_back(r - bound);
    else if (r < bound + linear + 2 * static_cast<int>(n)) active_.box.push_back(r - bound - linear);
  }
}

void EffortSqp::keepMultipliers(const Eigen::VectorXd& all) {
  const auto bound_rows = static_cast<Eigen::Index>(rows_at_theta_.value.size());
  bound_multipliers_.assign(all.data(), all.data() + bound_rows);
  linear_multipliers_ = all.segment(bound_rows, p_.linear.G.rows());
}

bool EffortSqp::fail(std::string why) {
  failure_ = std::move(why);
  return false;
}

}  // namespace flatsos::planner::detail
