#pragma once
// The sequential QP that minimizes a nonlinear effort (effort_model.hpp) over the flat outputs'
// coefficients theta at fixed rows: linear rows G theta >= row_lower and theta's box (the
// reserves and Y >= 0 of an exchange), and the bound rows of a and n at their points (nonlinear,
// linearized at each step, with a second-order correction where a full step leaves them). The
// open-loop plan's exchange (sos/effort_exchange.hpp) and the free joint path's value function
// (path/free_path.cpp) run it at their rows.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "bounds/bound_rows.hpp"
#include "bounds/effort_model.hpp"
#include "flatsos/planner/numerics/linear_program.hpp"
#include "numerics/dense_qp.hpp"

namespace flatsos::planner::detail {

/// What the sequential QP minimizes and keeps: all by reference, owned by the caller (the rows
/// may change between descend calls, as an exchange adds points).
struct EffortSqpProblem {
  const FlatOutputMap& flat;
  const Effort& effort;
  const std::vector<BoundPoint>& effort_points;  // the effort's quadrature points
  const std::vector<double>& weights_s;          // and weights
  const LinearProgram& linear;                   // G, row_lower, x_lower, x_upper (its cost unused)
  /// A linear row counts as met while G theta >= row_lower - linear_slack.
  double linear_slack = 0.0;
  const std::vector<BoundPoint>& bound_points;
  const Eigen::VectorXd& a_min;
};

/// A QP's active rows by kind, each index within its block: the bound rows (per point, muscle
/// and row: they keep their index as points are appended), the linear rows, theta's box (lower,
/// then upper). What the next QP starts from, in a later descend or another EffortSqp.
struct EffortSqpActiveRows {
  std::vector<int> bound, linear, box;
};

class EffortSqp {
 public:
  explicit EffortSqp(const EffortSqpProblem& problem) : p_(problem) {}

  /// The effort and its model at theta; false where it is not defined.
  bool start(const Eigen::VectorXd& theta);
  /// QP steps from theta (start() called there) at the current rows until the effort's decrease
  /// is negligible inside them, counting them in `steps` (at most max_steps over all calls).
  /// False with failure() when the rows cannot be reached, a QP fails or the steps run out.
  bool descend(Eigen::VectorXd& theta, int& steps, int max_steps);
  /// The rows the next QP starts from (another run's activeRows(): a QP started without any
  /// added thousands of rows one by one where one started from its neighbour's added a few).
  void startFrom(EffortSqpActiveRows rows) { active_ = std::move(rows); }
  /// The last QP's active rows.
  const EffortSqpActiveRows& activeRows() const { return active_; }
  /// Rows the QPs added or dropped so far (their active-set changes): the QPs' work.
  int qpRowChanges() const { return qp_row_changes_; }

  const EffortModel& model() const { return model_; }
  const std::string& failure() const { return failure_; }
  /// The last QP's multipliers (>= 0) of the bound rows (per point, muscle, row) and of the
  /// linear rows: at convergence the problem's KKT multipliers.
  const std::vector<double>& boundRowMultipliers() const { return bound_multipliers_; }
  const Eigen::VectorXd& linearRowMultipliers() const { return linear_multipliers_; }

 private:
  double violation(const Eigen::VectorXd& theta) const;
  void qpRows(const Eigen::VectorXd& theta, SparseRows& J, Eigen::VectorXd& lower);
  double predictedDecrease(const Eigen::VectorXd& d) const;
  bool lineSearch(const Eigen::VectorXd& d, Eigen::VectorXd& theta, double& current);
  bool correctedStep(const Eigen::VectorXd& theta, const Eigen::MatrixXd& H, const SparseRows& J,
                     const Eigen::VectorXd& lower, Eigen::VectorXd& d, std::vector<int>& hint);
  void keepMultipliers(const Eigen::VectorXd& all);
  // active_ as row indices of the QP qpRows built (entries beyond their block left out), and back.
  std::vector<int> qpHint(Eigen::Index n) const;
  void keepActive(const std::vector<int>& rows, Eigen::Index n);
  bool fail(std::string why);

  const EffortSqpProblem& p_;
  EffortModel model_;
  BoundRowsAt rows_at_theta_;  // the bound rows at theta, as the last QP linearized them
  DenseQpWorkspace qp_;
  EffortSqpActiveRows active_;
  std::vector<Eigen::Triplet<double>> triplets_;  // qpRows' scratch
  // The linear rows' nonzeros (row within their block), taken from G once per descend: G is fixed
  // there (the arm's squared free path 14.7 -> 14.4 s).
  std::vector<Eigen::Triplet<double>> linear_entries_;
  int qp_row_changes_ = 0;
  std::vector<double> bound_multipliers_;
  Eigen::VectorXd linear_multipliers_;
  std::string failure_;
};

}  // namespace flatsos::planner::detail
