#include "bounds/active_set_newton.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>

namespace flatsos::planner::detail {

namespace {
// Below this reciprocal condition the active gradients do not span the space: no vertex.
constexpr double kMinReciprocalCondition = 1e-12;
// A residual this small before a step leaves a residual near rounding after it (quadratic
// convergence): the next rows are evaluated without their Jacobian.
constexpr double kLastStepResidual = 1e-6;
// Stationary along the free directions once Newton's step there is shorter than this relative
// to theta's size (a cost decrease is no measure: the cost is flat to second order there).
constexpr double kStationaryStep = 1e-10;
// A row the linearized step leaves further below zero than this joins the active set; smaller
// violations are within what the rows accept (kBoundMargin) once the step is taken.
constexpr double kJoiningRow = 0.1 * kBoundMargin;

ActiveSetNewtonOutcome fail(ActiveSetNewtonOutcome out, std::string why) {
  out.solved = false;
  out.why_not = std::move(why);
  return out;
}

// The active set's step at the rows' last linearization: with m active rows of gradients
// J (m x p) and J^T P = Q [R; 0] (column-pivoted QR), the normal step d_n = Q1 u, R^T u = -P^T v,
// zeroes the linearized active rows with the least move; the multipliers y = P R^-1 Q1^T cost
// fit cost = J^T y; and with m < p the step along Z = Q2 (the directions that keep the active
// rows) is Newton's on the Lagrangian cost - y . rows, whose Hessian along Z comes from the active
// rows' curvature (the null-space method of SQP, the cross term Z^T W d_n left out: Nocedal and
// Wright, Numerical Optimization, 2nd ed., section 18.3). With m = p it is the vertex's step.
class Linearization {
 public:
  Linearization(const ActiveSetRows& rows, std::vector<int>& active, std::vector<int>& position)
      : rows_(rows), active_(active), position_(position) {}

  // The step at the active set, taking in the rows the step would leave below zero until none
  // does: while m < p a row simply joins, at a vertex by a dual simplex pivot (the active row
  // whose release raises the joining row at the least cost leaves). False when the active
  // gradients are dependent, no row bounds the cost along Z, the point is a saddle along Z, no
  // vertex nearby meets a row, or `max_pivots` is reached.
  bool step(const Eigen::VectorXd& cost, int max_pivots, Eigen::VectorXd& d, int& pivots, std::string& why) {
    const std::vector<double>& value = rows_.values();
    for (;;) {
      if (!factor(cost, why)) return false;
      d = normal_;
      rows_.change(d, change_);
      int joining = -1;
      double worst = -kJoiningRow;
      for (std::size_t i = 0; i < value.size(); ++i)
        if (position_[i] < 0 && value[i] + change_[i] < worst) worst = value[i] + change_[i], joining = static_cast<int>(i);
      if (joining < 0 && !tangential(cost, d, joining, why)) return false;
      if (joining < 0) return true;
      if (pivots == max_pivots) return refuse(why, "too many rows join the active set");
      ++pivots;
      if (!pivot(joining, why)) return false;
    }
  }
  /// After step(): the multipliers and the length of the step along Z (0 at a vertex).
  const Eigen::VectorXd& multipliers() const { return y_; }
  double tangentialStep() const { return tangential_step_; }

 private:
  static bool refuse(std::string& why, const char* reason) {
    why = reason;
    return false;
  }

  // QR of the active gradients, the normal step and the multipliers.
  bool factor(const Eigen::VectorXd& cost, std::string& why) {
    const auto m = static_cast<Eigen::Index>(active_.size()), p = cost.size();
    if (m == 0 || m > p) return refuse(why, "the active set has no rows or more than theta.size()");
    Eigen::MatrixXd Jt(p, m);
    Eigen::VectorXd v(m), g(p);
    for (Eigen::Index k = 0; k < m; ++k) {
      const auto row = static_cast<std::size_t>(active_[static_cast<std::size_t>(k)]);
      rows_.gradient(row, g);
      Jt.col(k) = g;
      v[k] = rows_.values()[row];
    }
    vertex_ = m == p;
    if (vertex_) {
      // A vertex (the receding horizon's usual case): LU, cheaper than the QR and its Q.
      lu_.compute(Jt.transpose());
      if (!(lu_.rcond() > kMinReciprocalCondition)) return refuse(why, "the active rows' gradients are (nearly) dependent");
      normal_ = -lu_.solve(v);
    } else {
      qr_.compute(Jt);
      // Column pivoting orders R's diagonal by size: its last over its first bounds the condition.
      if (!(std::abs(qr_.matrixQR()(m - 1, m - 1)) > kMinReciprocalCondition * std::abs(qr_.matrixQR()(0, 0))))
        return refuse(why, "the active rows' gradients are (nearly) dependent");
      Q_ = qr_.householderQ();
      const Eigen::VectorXd u =
          -qr_.matrixQR().topLeftCorner(m, m).triangularView<Eigen::Upper>().transpose().solve(qr_.colsPermutation().transpose() * v);
      normal_ = Q_.leftCols(m) * u;
    }
    y_ = inRange(cost);
    return true;
  }
  // The active multipliers of b's part in their gradients' span: J^-T b at a vertex, else
  // P R^-1 Q1^T b.
  Eigen::VectorXd inRange(const Eigen::VectorXd& b) const {
    if (vertex_) return lu_.transpose().solve(b);
    const auto m = static_cast<Eigen::Index>(active_.size());
    const Eigen::VectorXd r = qr_.matrixQR().topLeftCorner(m, m).triangularView<Eigen::Upper>().solve(Q_.leftCols(m).transpose() * b);
    return qr_.colsPermutation() * r;
  }

  // Adds Newton's step along the free directions Z to d (nothing at a vertex), or where a row
  // off the active set would block it (the first one the step meets), names that row in
  // `joining`. Where the Lagrangian does not curve up along Z the cost falls along -Z Z^T cost
  // until a row blocks it (the primal simplex's ratio test, when the active rows are flat there).
  bool tangential(const Eigen::VectorXd& cost, Eigen::VectorXd& d, int& joining, std::string& why) {
    const auto m = static_cast<Eigen::Index>(active_.size()), p = cost.size(), free = p - m;
    tangential_step_ = 0.0;
    if (free == 0) return true;
    const Eigen::MatrixXd Z = Q_.rightCols(free);
    Eigen::MatrixXd WZ(p, free);
    Eigen::VectorXd column;
    for (Eigen::Index j = 0; j < free; ++j) {
      rows_.curvature(active_, -y_, Z.col(j), column);  // W = -sum y_i Hessian_i
      WZ.col(j) = column;
    }
    Eigen::MatrixXd H = Z.transpose() * WZ;
    H = 0.5 * (H + H.transpose()).eval();
    const Eigen::VectorXd r = Z.transpose() * cost;
    const Eigen::LLT<Eigen::MatrixXd> llt(H);
    const bool newton = llt.info() == Eigen::Success;
    if (!newton && r.norm() <= 1e-14 * cost.norm())
      return refuse(why, "the active rows do not curve the cost up along their free directions");
    const Eigen::VectorXd along = newton ? Eigen::VectorXd(-Z * llt.solve(r)) : Eigen::VectorXd(-Z * r);
    const double reach = newton ? 1.0 : std::numeric_limits<double>::infinity();
    const double t = blocked_at(along, reach, joining);
    if (joining >= 0) return true;
    if (!std::isfinite(t)) return refuse(why, "no row bounds the cost along the active rows' free directions");
    tangential_step_ = along.cwiseAbs().maxCoeff();
    d += along;
    return true;
  }
  // How far along `along` (from the normal step, whose changes are in change_) the rows off the
  // active set allow, up to `reach`; the first row met into `blocking` (-1: none within reach).
  double blocked_at(const Eigen::VectorXd& along, double reach, int& blocking) {
    const std::vector<double>& value = rows_.values();
    rows_.change(along, change_along_);
    double t = reach;
    blocking = -1;
    for (std::size_t i = 0; i < value.size(); ++i) {
      if (position_[i] >= 0 || change_along_[i] >= 0.0) continue;
      const double t_i = std::max(0.0, value[i] + change_[i] + kJoiningRow) / -change_along_[i];
      if (t_i < t) t = t_i, blocking = static_cast<int>(i);
    }
    return t;
  }

  // Row `joining` enters the active set; at a vertex the dual simplex picks the row that leaves.
  bool pivot(int joining, std::string& why) {
    if (!vertex_) {
      const auto m = active_.size();
      position_[static_cast<std::size_t>(joining)] = static_cast<int>(m);
      active_.push_back(joining);
      return true;
    }
    const auto m = static_cast<Eigen::Index>(active_.size());  // = theta.size() at a vertex
    Eigen::VectorXd g(m);
    rows_.gradient(static_cast<std::size_t>(joining), g);
    const Eigen::VectorXd w = inRange(g);
    const double tiny = 1e-12 * w.cwiseAbs().maxCoeff();
    Eigen::Index leaving = -1;
    double best = 0.0;
    for (Eigen::Index k = 0; k < m; ++k)
      if (w[k] > tiny && (leaving < 0 || std::max(y_[k], 0.0) / w[k] < best)) best = std::max(y_[k], 0.0) / w[k], leaving = k;
    if (leaving < 0) return refuse(why, "no vertex nearby meets a violated row");
    position_[static_cast<std::size_t>(active_[static_cast<std::size_t>(leaving)])] = -1;
    active_[static_cast<std::size_t>(leaving)] = joining;
    position_[static_cast<std::size_t>(joining)] = static_cast<int>(leaving);
    return true;
  }

  const ActiveSetRows& rows_;
  std::vector<int>& active_;
  std::vector<int>& position_;
  std::vector<double> change_, change_along_;  // rows' changes along the normal step, along Z's step
  bool vertex_ = false;  // m = p: factored by lu_, else by qr_ (with Q_ formed)
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr_;
  Eigen::MatrixXd Q_;
  Eigen::VectorXd normal_, y_;
  double tangential_step_ = 0.0;
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

std::vector<int> active_rows(const SequentialLpOutcome& outcome, const Eigen::VectorXd& theta,
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
  if (static_cast<Eigen::Index>(active.size()) > p) active.clear();
  return active;
}

WithLinearRows::WithLinearRows(ActiveSetRows& bound, const LinearProgram& lp) : bound_(bound), lp_(lp) {}

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

void WithLinearRows::curvature(const std::vector<int>& rows, const Eigen::VectorXd& weight, const Eigen::VectorXd& z,
                               Eigen::VectorXd& out) const {
  // The linear rows are flat: only the bound rows among `rows` curve.
  std::vector<int> bound_rows;
  std::vector<double> bound_weight;
  const auto n = static_cast<int>(bound_.values().size());
  for (std::size_t k = 0; k < rows.size(); ++k)
    if (rows[k] < n) bound_rows.push_back(rows[k]), bound_weight.push_back(weight[static_cast<Eigen::Index>(k)]);
  bound_.curvature(bound_rows, Eigen::Map<const Eigen::VectorXd>(bound_weight.data(), static_cast<Eigen::Index>(bound_weight.size())),
                   z, out);
}

ActiveSetRowsOf::ActiveSetRowsOf(const NonlinearRows& rows, const Eigen::VectorXd& x) : rows_(rows) { evaluate(x, true); }

void ActiveSetRowsOf::evaluate(const Eigen::VectorXd& x, bool gradients) {
  x_ = x;
  at_ = rows_(x, gradients);
  gradients_ = gradients;
  if (gradients) by_row_ = JacobianByRow(at_);
}

void ActiveSetRowsOf::requireGradients() const {
  if (!gradients_) throw std::logic_error("active-set rows: gradients asked of rows evaluated without them");
}

void ActiveSetRowsOf::gradient(std::size_t row, Eigen::Ref<Eigen::VectorXd> out) const {
  requireGradients();
  by_row_.copy_row(row, out);
}

void ActiveSetRowsOf::change(const Eigen::VectorXd& d, std::vector<double>& out) const {
  requireGradients();
  out.resize(at_.value.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = by_row_.dot(i, d);
}

void ActiveSetRowsOf::curvature(const std::vector<int>& rows, const Eigen::VectorXd& weight, const Eigen::VectorXd& z,
                             Eigen::VectorXd& out) const {
  out = Eigen::VectorXd::Zero(x_.size());
  const double h = curvature_step(x_, z);
  if (h == 0.0) return;
  const JacobianByRow plus(rows_(x_ + h * z, true)), minus(rows_(x_ - h * z, true));
  Eigen::VectorXd g_plus(x_.size()), g_minus(x_.size());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    plus.copy_row(static_cast<std::size_t>(rows[k]), g_plus);
    minus.copy_row(static_cast<std::size_t>(rows[k]), g_minus);
    out += weight[static_cast<Eigen::Index>(k)] / (2.0 * h) * (g_plus - g_minus);
  }
}

double curvature_step(const Eigen::VectorXd& x, const Eigen::VectorXd& z) {
  const double size = z.size() ? z.cwiseAbs().maxCoeff() : 0.0;
  return size > 0.0 ? 6e-6 * (1.0 + x.cwiseAbs().maxCoeff()) / size : 0.0;
}

ActiveSetNewtonOutcome solve_on_active_set(const SequentialLpLinearPart& linear, ActiveSetRows& rows, std::vector<int>& active,
                                    Eigen::VectorXd& theta, const ActiveSetNewtonSettings& settings) {
  ActiveSetNewtonOutcome out;
  const LinearProgram& lp = linear.lp;
  const Eigen::Index p = theta.size();
  if (active.empty() || static_cast<Eigen::Index>(active.size()) > p)
    return fail(out, "the active set is empty or has more rows than theta has entries");
  std::vector<int> position(rows.values().size(), -1);
  for (std::size_t k = 0; k < active.size(); ++k) {
    const int row = active[k];
    if (row < 0 || static_cast<std::size_t>(row) >= position.size() || position[static_cast<std::size_t>(row)] >= 0)
      return fail(out, "the active set names a row twice or one the rows do not have");
    position[static_cast<std::size_t>(row)] = static_cast<int>(k);
  }

  Eigen::VectorXd x = theta, d;
  Linearization linearization(rows, active, position);
  // Converged: the active rows zero, every other row held as the sequential LP holds it, and
  // nothing left to gain along the active rows' free directions.
  auto rows_converged = [&] {
    return largest_active(rows.values(), active) <= settings.row_tolerance &&
           worst_row_off(rows.values(), position) >= -kBoundMargin;
  };
  auto tangential_below = [&](double relative) {
    return linearization.tangentialStep() <= relative * (1.0 + x.cwiseAbs().maxCoeff());
  };
  std::string why;
  bool gradients_at_x = true;
  for (;;) {
    if (gradients_at_x && !linearization.step(lp.cost, settings.max_pivots, d, out.pivots, why)) return fail(out, why);
    if (rows_converged() && tangential_below(kStationaryStep)) break;
    if (out.iterations == settings.max_iterations) return fail(out, "Newton's method did not converge");
    const bool last_likely = largest_active(rows.values(), active) <= kLastStepResidual && tangential_below(kLastStepResidual);
    x += d;
    ++out.iterations;
    if (!x.allFinite()) return fail(out, "a Newton step is not finite");
    rows.evaluate(x, !last_likely);
    const std::vector<double>& value = rows.values();
    if (!std::all_of(value.begin(), value.end(), [](double v) { return std::isfinite(v); }))
      return fail(out, "the rows are not finite after a Newton step");
    gradients_at_x = !last_likely;
    if (last_likely) {
      if (rows_converged()) break;  // quadratic convergence: the last linearization's multipliers hold
      rows.evaluate(x, true);       // not quadratic after all: its gradients
      gradients_at_x = true;
    }
  }
  theta = x;
  out.converged = true;

  // Every reserve row holds as the sequential LP requires of its own result (rowsHold), and x its bounds.
  if (lp.G.rows() > 0 && !((lp.G * x - lp.row_lower).minCoeff() >= -0.5 * linear.reserve_margin_N))
    return fail(out, "a reserve row is violated at the end of Newton's method");
  if ((x.array() < lp.x_lower.array()).any() || (x.array() > lp.x_upper.array()).any())
    return fail(out, "Newton's method leaves theta's bounds");
  // cost = J^T y with y >= 0, J the active rows' gradients at the last linearization (within a
  // Newton step of the end).
  const Eigen::VectorXd& y = linearization.multipliers();
  if (!y.allFinite() || (y.array() < 0.0).any()) return fail(out, "a multiplier is negative: not the optimum's active set");
  out.solved = true;
  return out;
}

}  // namespace flatsos::planner::detail
