#pragma once
// Newton's method on a known active set of the bounds' problem (sequential_lp.hpp). With a
// linear cost a nondegenerate optimum is usually a vertex: as many rows active (zero) as theta
// has entries (bound rows, and the linear rows beside them: reserve rows, theta's lower bounds).
// A receding horizon's consecutive periods keep most of their active rows: holding them at zero
// by Newton's method (one dense p x p solve per iteration) reaches the new optimum in two or three
// evaluations of the rows, where the sequential LP takes as many LP steps, each with its rows,
// their Jacobian by rows and a simplex solve. A row the linearized step would leave below zero
// joins the vertex by a dual simplex pivot on the same linearization (the row whose release
// raises it at the least cost leaves), as the sequential LP's step LP would.
//
// Where the optimum sits on curved rows with fewer active rows than theta has entries, the
// sequential LP converges only linearly (its trust region halves step after step); here the
// step along the directions the active rows leave free is Newton's on the Lagrangian, from the
// rows' curvature along them (the null-space method of SQP), and the first row it meets joins.
//
// The point is accepted only as a KKT point of the whole problem: every bound row and reserve
// row holds (as the sequential LP requires of its own result), the cost is a nonnegative
// combination of the active rows' gradients and, off a vertex, the Lagrangian curves up along
// the free directions. That makes it a strict local minimum, the kind of point the sequential
// LP converges to. Otherwise the caller runs the sequential LP.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "bounds/sequential_lp.hpp"

namespace flatsos::planner::detail {

/// What Newton's method on an active set asks of the rows at a point x: their values and, after
/// an evaluation with gradients, a row's gradient in theta, every row's change along a step and
/// the active rows' curvature along a direction.
class ActiveSetRows {
 public:
  virtual ~ActiveSetRows() = default;
  /// The rows at x (and what gradient() and change() need when `gradients`).
  virtual void evaluate(const Eigen::VectorXd& x, bool gradients) = 0;
  virtual const std::vector<double>& values() const = 0;
  /// Row `row`'s gradient into `out` (theta.size() entries, set beforehand).
  virtual void gradient(std::size_t row, Eigen::Ref<Eigen::VectorXd> out) const = 0;
  /// out[i] = gradient of row i . d, for every row.
  virtual void change(const Eigen::VectorXd& d, std::vector<double>& out) const = 0;
  /// out = sum_k weight[k] (Hessian of row rows[k]) z at the last evaluation's x (by central
  /// differences of the rows' gradients: the rows give first derivatives only).
  virtual void curvature(const std::vector<int>& rows, const Eigen::VectorXd& weight, const Eigen::VectorXd& z,
                         Eigen::VectorXd& out) const = 0;
};

/// The step of central differences along z for a curvature at x: a cube root of the
/// machine epsilon relative to x's scale, which balances truncation and rounding.
double curvature_step(const Eigen::VectorXd& x, const Eigen::VectorXd& z);

/// ActiveSetRows of NonlinearRows through their Jacobian by rows; their curvature by central
/// differences of two more evaluations.
class ActiveSetRowsOf final : public ActiveSetRows {
 public:
  /// Evaluated at x with gradients.
  ActiveSetRowsOf(const NonlinearRows& rows, const Eigen::VectorXd& x);
  void evaluate(const Eigen::VectorXd& x, bool gradients) override;
  const std::vector<double>& values() const override { return at_.value; }
  void gradient(std::size_t row, Eigen::Ref<Eigen::VectorXd> out) const override;
  void change(const Eigen::VectorXd& d, std::vector<double>& out) const override;
  void curvature(const std::vector<int>& rows, const Eigen::VectorXd& weight, const Eigen::VectorXd& z,
                 Eigen::VectorXd& out) const override;

 private:
  void requireGradients() const;  // throws std::logic_error after an evaluation without them
  const NonlinearRows& rows_;
  Eigen::VectorXd x_;
  BoundRowsAt at_;
  JacobianByRow by_row_;
  bool gradients_ = true;  // the last evaluation's
};

/// Bound rows and, numbered after them, the linear rows of an LP: its rows G x >= row_lower
/// (value G x - row_lower, in their own units: the reserve rows) and then x >= x_lower, which
/// share the active set with the bound rows while the plan moves.
class WithLinearRows final : public ActiveSetRows {
 public:
  /// Keeps references to both.
  WithLinearRows(ActiveSetRows& bound, const LinearProgram& lp);
  void evaluate(const Eigen::VectorXd& x, bool gradients) override;
  const std::vector<double>& values() const override { return value_; }
  void gradient(std::size_t row, Eigen::Ref<Eigen::VectorXd> out) const override;
  void change(const Eigen::VectorXd& d, std::vector<double>& out) const override;
  void curvature(const std::vector<int>& rows, const Eigen::VectorXd& weight, const Eigen::VectorXd& z,
                 Eigen::VectorXd& out) const override;

 private:
  ActiveSetRows& bound_;
  const LinearProgram& lp_;
  std::vector<double> value_;
};

struct ActiveSetNewtonSettings {
  int max_iterations = 6;  ///< Newton steps
  int max_pivots = 20;     ///< rows joining the active set, over all steps
  double row_tolerance = 1e-10;  ///< |active row| at the end, in the rows' units (activation)
};

struct ActiveSetNewtonOutcome {
  bool converged = false;  ///< the active rows are zero at theta (which has moved there)
  bool solved = false;     ///< ... and it is the KKT point described above
  int iterations = 0;  ///< Newton steps
  int pivots = 0;      ///< rows that joined the active set
  std::string why_not;  ///< what failed, for studies and tests
};

/// The active set of a sequential LP converged at theta: its bound rows, then its reserve rows
/// (numbered after the bound rows, as in WithLinearRows) with positive multipliers, then the
/// entries of theta at their lower bound (numbered after the reserve rows), when they are at
/// most theta.size(); empty otherwise.
std::vector<int> active_rows(const SequentialLpOutcome& outcome, const Eigen::VectorXd& theta,
                             const Eigen::VectorXd& theta_lower);

/// From theta, where `rows` were last evaluated with gradients, moves theta to where the rows
/// `active` (indices into the rows, 1 to theta.size() of them; rows join it, and leave it at a
/// vertex) are zero and the cost is stationary along them, then checks the KKT conditions above.
/// theta is moved once Newton's method converges, whether or not the point passes: the
/// sequential LP then starts there.
ActiveSetNewtonOutcome solve_on_active_set(const SequentialLpLinearPart& linear, ActiveSetRows& rows,
                                           std::vector<int>& active, Eigen::VectorXd& theta,
                                           const ActiveSetNewtonSettings& settings = {});

}  // namespace flatsos::planner::detail
