#include "bounds/vertex_newton.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/LU>

namespace flatsos::planner::detail {

namespace {
// Below this reciprocal condition the active gradients do not span the space: no vertex.
constexpr double kMinReciprocalCondition = 1e-12;
// A residual this small before a step leaves a residual near rounding after it (quadratic
// convergence): the next rows are evaluated without their Jacobian.
constexpr double kLastStepResidual = 1e-6;
// A row the linearized step leaves further below zero than this joins the vertex; smaller
// violations are within what the rows accept (kBoundMargin) once the step is taken.
constexpr double kJoiningRow = 0.1 * kBoundMargin;

VertexNewtonOutcome fail(VertexNewtonOutcome out, std::string why) {
  out.solved = false;
  out.why_not = std::move(why);
  return out;
}

// The vertex's step at the rows' last linearization.
class Linearization {
 public:
  Linearization(const VertexRows& rows, std::vector<int>& active, std::vector<int>& position)
      : rows_(rows), active_(active), position_(position) {}

  // The step that zeroes the vertex's linearized rows, taking in (by the dual simplex) the rows
  // that step would leave below zero until none does. False when the vertex's gradients are
  // dependent, no vertex nearby meets a row, or `max_pivots` is reached.
  bool step(const Eigen::VectorXd& cost, int max_pivots, Eigen::VectorXd& d, int& pivots, std::string& why) {
    const auto p = static_cast<Eigen::Index>(active_.size());
    const std::vector<double>& value = rows_.values();
    Eigen::MatrixXd J(p, p);
    Eigen::VectorXd v(p), g(p);
    for (;;) {
      for (Eigen::Index k = 0; k < p; ++k) {
        const auto row = static_cast<std::size_t>(active_[static_cast<std::size_t>(k)]);
        rows_.gradient(row, g);
        J.row(k) = g.transpose();
        v[k] = value[row];
      }
      lu_.compute(J);
      if (!(lu_.rcond() > kMinReciprocalCondition)) return refuse(why, "the active rows' gradients are (nearly) dependent");
      d = -lu_.solve(v);
      rows_.change(d, change_);
      int joining = -1;
      double worst = -kJoiningRow;
      for (std::size_t i = 0; i < value.size(); ++i)
        if (position_[i] < 0 && value[i] + change_[i] < worst) worst = value[i] + change_[i], joining = static_cast<int>(i);
      if (joining < 0) return true;
      if (pivots == max_pivots) return refuse(why, "too many rows join the vertex");
      // Dual simplex: the leaving row k is the one whose release raises the joining row at the
      // least cost per unit (min y_k / w_k over w_k > 0), which keeps every multiplier >= 0.
      rows_.gradient(static_cast<std::size_t>(joining), g);
      const Eigen::VectorXd w = lu_.transpose().solve(g), y = lu_.transpose().solve(cost);
      const double tiny = 1e-12 * w.cwiseAbs().maxCoeff();
      Eigen::Index leaving = -1;
      double best = 0.0;
      for (Eigen::Index k = 0; k < p; ++k)
        if (w[k] > tiny && (leaving < 0 || std::max(y[k], 0.0) / w[k] < best)) best = std::max(y[k], 0.0) / w[k], leaving = k;
      if (leaving < 0) return refuse(why, "no vertex nearby meets a violated row");
      position_[static_cast<std::size_t>(active_[static_cast<std::size_t>(leaving)])] = -1;
      active_[static_cast<std::size_t>(leaving)] = joining;
      position_[static_cast<std::size_t>(joining)] = static_cast<int>(leaving);
      ++pivots;
    }
  }
  // The vertex's gradients at this linearization, factored (after step()).
  const Eigen::PartialPivLU<Eigen::MatrixXd>& factors() const { return lu_; }

 private:
  static bool refuse(std::string& why, const char* reason) {
    why = reason;
    return false;
  }
  const VertexRows& rows_;
  std::vector<int>& active_;
  std::vector<int>& position_;
  std::vector<double> change_;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_;
};

double worst_row_off(const std::vector<double>& value, const std::vector<int>& position) {
  double worst = 0.0;
  for (std::size_t i = 0; i < value.size(); ++i)
    if (position[i] < 0) worst = std::min(worst, value[i]);
  return worst;
}

double largest_active(const std::vector<double>& value, const std::vector<int>& active) {
  double largest = 0.0;
  for (const int row : active) largest = std::max(largest, std::abs(value[static_cast<std::size_t>(row)]));
  return largest;
}
}  // namespace

std::vector<int> vertex_rows(const SequentialLpOutcome& outcome, const Eigen::VectorXd& theta,
                             const Eigen::VectorXd& theta_lower) {
  const Eigen::Index p = theta.size();
  std::vector<int> active;
  if (!outcome.converged || outcome.rows_violated) return active;
  for (std::size_t i = 0; i < outcome.row_multipliers.size(); ++i)
    if (outcome.row_multipliers[i] > 0.0) active.push_back(static_cast<int>(i));
  const auto bound_rows = static_cast<int>(outcome.row_multipliers.size());
  for (Eigen::Index r = 0; r < outcome.linear_row_multipliers.size(); ++r)
    if (outcome.linear_row_multipliers[r] > 0.0) active.push_back(bound_rows + static_cast<int>(r));
  // The step LPs end exactly on theta's bounds (up to rounding of theta + d): no multiplier is kept for them.
  const int first_bound = bound_rows + static_cast<int>(outcome.linear_row_multipliers.size());
  for (Eigen::Index i = 0; i < p; ++i)
    if (theta[i] - theta_lower[i] <= 1e-12 * (1.0 + std::abs(theta[i]))) active.push_back(first_bound + static_cast<int>(i));
  if (static_cast<Eigen::Index>(active.size()) != p) active.clear();
  return active;
}

WithLinearRows::WithLinearRows(VertexRows& bound, const LinearProgram& lp) : bound_(bound), lp_(lp) {}

void WithLinearRows::evaluate(const Eigen::VectorXd& x, bool gradients) {
  bound_.evaluate(x, gradients);
  value_ = bound_.values();
  const Eigen::VectorXd reserve = lp_.G * x - lp_.row_lower;
  value_.insert(value_.end(), reserve.data(), reserve.data() + reserve.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) value_.push_back(x[i] - lp_.x_lower[i]);
}

void WithLinearRows::gradient(std::size_t row, Eigen::Ref<Eigen::VectorXd> out) const {
  const std::size_t n = bound_.values().size(), reserves = static_cast<std::size_t>(lp_.G.rows());
  if (row < n) {
    bound_.gradient(row, out);
  } else if (row < n + reserves) {
    out = lp_.G.row(static_cast<Eigen::Index>(row - n)).transpose();
  } else {
    out.setZero();
    out[static_cast<Eigen::Index>(row - n - reserves)] = 1.0;
  }
}

void WithLinearRows::change(const Eigen::VectorXd& d, std::vector<double>& out) const {
  bound_.change(d, out);
  const Eigen::VectorXd reserve = lp_.G * d;
  out.insert(out.end(), reserve.data(), reserve.data() + reserve.size());
  out.insert(out.end(), d.data(), d.data() + d.size());
}

VertexRowsOf::VertexRowsOf(const NonlinearRows& rows, BoundRowsAt at_start)
    : rows_(rows), at_(std::move(at_start)), by_row_(at_), gradients_(!at_.jacobian.empty() || at_.value.empty()) {}

void VertexRowsOf::evaluate(const Eigen::VectorXd& x, bool gradients) {
  at_ = rows_(x, gradients);
  gradients_ = gradients;
  if (gradients) by_row_ = JacobianByRow(at_);
}

void VertexRowsOf::requireGradients() const {
  if (!gradients_) throw std::logic_error("vertex rows: gradients asked of rows evaluated without them");
}

void VertexRowsOf::gradient(std::size_t row, Eigen::Ref<Eigen::VectorXd> out) const {
  requireGradients();
  by_row_.copy_row(row, out);
}

void VertexRowsOf::change(const Eigen::VectorXd& d, std::vector<double>& out) const {
  requireGradients();
  out.resize(at_.value.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = by_row_.dot(i, d);
}

VertexNewtonOutcome solve_on_vertex(const SequentialLpLinearPart& linear, VertexRows& rows, std::vector<int>& active,
                                    Eigen::VectorXd& theta, const VertexNewtonSettings& settings) {
  VertexNewtonOutcome out;
  const LinearProgram& lp = linear.lp;
  const Eigen::Index p = theta.size();
  if (static_cast<Eigen::Index>(active.size()) != p) return fail(out, "the active set has other than theta.size() rows");
  std::vector<int> position(rows.values().size(), -1);
  for (std::size_t k = 0; k < active.size(); ++k) {
    const int row = active[k];
    if (row < 0 || static_cast<std::size_t>(row) >= position.size() || position[static_cast<std::size_t>(row)] >= 0)
      return fail(out, "the active set names a row twice or one the rows do not have");
    position[static_cast<std::size_t>(row)] = static_cast<int>(k);
  }

  Eigen::VectorXd x = theta, d;
  Linearization linearization(rows, active, position);
  // Converged: the vertex's rows zero and every other row held as the sequential LP holds it.
  auto converged = [&] {
    return largest_active(rows.values(), active) <= settings.row_tolerance &&
           worst_row_off(rows.values(), position) >= -kBoundMargin;
  };
  bool done = converged();
  std::string why;
  int no_pivots = 0;  // on the vertex from the start: its factors for the multipliers, as it is
  if (done && !linearization.step(lp.cost, 0, d, no_pivots, why)) return fail(out, why);
  while (!done) {
    if (out.iterations == settings.max_iterations) return fail(out, "Newton's method did not converge");
    const bool last_likely = largest_active(rows.values(), active) <= kLastStepResidual;
    if (!linearization.step(lp.cost, settings.max_pivots, d, out.pivots, why)) return fail(out, why);
    x += d;
    ++out.iterations;
    if (!x.allFinite()) return fail(out, "a Newton step is not finite");
    rows.evaluate(x, !last_likely);
    const std::vector<double>& value = rows.values();
    if (!std::all_of(value.begin(), value.end(), [](double v) { return std::isfinite(v); }))
      return fail(out, "the rows are not finite after a Newton step");
    done = converged();
    if (!done && last_likely) rows.evaluate(x, true);  // not quadratic after all: its gradients
  }
  theta = x;
  out.converged = true;

  // Every reserve row holds as the sequential LP requires of its own result (rowsHold), and x its bounds.
  if (lp.G.rows() > 0 && !((lp.G * x - lp.row_lower).minCoeff() >= -0.5 * linear.reserve_margin_N))
    return fail(out, "a reserve row is violated at the vertex");
  if ((x.array() < lp.x_lower.array()).any() || (x.array() > lp.x_upper.array()).any())
    return fail(out, "the vertex leaves theta's bounds");
  // cost = J^T y with y >= 0, J the vertex's gradients at the last linearization (within a
  // Newton step of the vertex).
  const Eigen::VectorXd y = linearization.factors().transpose().solve(lp.cost);
  if (!y.allFinite() || (y.array() < 0.0).any()) return fail(out, "a multiplier is negative: not the optimum's vertex");
  out.solved = true;
  return out;
}

}  // namespace flatsos::planner::detail
