#pragma once
// Sequential linear programming with a trust region: the default solver of the bounds.
// The cost is linear and the optimum sits where as many constraints are active as there are free
// coefficients, so linearizing the bound rows at theta and solving the LP inside a box
// |d| <= Delta converges like Newton's method near the solution. Every row is elastic (a slack
// priced at `penalty` per unit), which keeps each LP feasible and makes the l1 merit
//   phi(theta) = cost . theta + penalty (sum of bound-row violations + reserve-row violations in N)
// an exact penalty once the penalty exceeds every multiplier; steps are accepted by the ratio of
// actual to predicted merit decrease. Near t = 0 the initial state pins the flat outputs, rows
// move little per newton and their multipliers are large: the penalty is steered by the LP of
// the violation alone (SequentialLpSettings::steering) and grows tenfold whenever the iteration settles
// with rows still violated. Where the violation is stationary the rows cannot be met from here:
// converged with rows_violated.

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "bounds/bound_rows.hpp"
#include "flatsos/planner/numerics/simplex_lp.hpp"

namespace flatsos::planner::detail {

struct SequentialLpOutcome {
  bool converged = false;
  bool rows_violated = false;  // settled with imposed rows violated although the LP paid for it at the largest penalty
  int iterations = 0, lp_pivots = 0;
  int lp_solves = 0;  // step LPs solved (more than iterations where rows joined a working set)
  long lp_rows = 0;   // their rows, summed
  std::string failure;
  /// The last step LP's multipliers (>= 0): per nonlinear row, then per row of the linear part's
  /// lp.G; 0 for rows that LP left out. At convergence they are the problem's KKT multipliers,
  /// which give the optimum's sensitivity to anything the rows depend on (free_path.cpp).
  std::vector<double> row_multipliers;
  Eigen::VectorXd linear_row_multipliers;
};

/// The linear part of the problem the bound rows join: minimize lp.cost . theta subject to
/// lp.G theta >= lp.row_lower (the reserve rows, kept as they are) and lp's variable bounds. The
/// reserve rows come in groups whose rows may be appended between calls (the exchange: one group
/// per constraint, a row per point): `rows_per_group` identifies each row for the basis.
struct SequentialLpLinearPart {
  const LinearProgram& lp;
  std::vector<std::size_t> rows_per_group;
  double reserve_margin_N = 0.0;        // reserve rows hold to half of this
};

/// The nonlinear rows ">= 0" at x, with their Jacobian when asked for. Rows keep their index
/// between calls and between rounds (new rows are appended), which the LP basis relies on.
using NonlinearRows = std::function<BoundRowsAt(const Eigen::VectorXd& x, bool jacobian)>;

struct SequentialLpSettings {
  int max_iterations = 100;         ///< LP steps
  /// Settles once the step LP predicts a merit decrease below this times (1 + |merit|) (and
  /// every row holds, or the penalty has done what it can).
  double relative_decrease = 1e-12;
  /// Each step LP starts from a working set of the rows that can reach zero inside the box (the
  /// violated ones, those active in the last LP and the `closest_rows_per_coefficient` x
  /// theta.size() closest others) and adds the rows its step would violate until none does: the
  /// same step as the LP over every such row. false: that LP itself (for comparison).
  bool working_set = true;
  /// 8: the leg's receding-horizon steps (37 coefficients, 1760 rows) took 4.2 ms with 2 (more
  /// LPs solved again as rows joined), 3.8 ms with 8, 4.0 with 16 (larger LPs).
  int closest_rows_per_coefficient = 8;
  /// While rows are violated, a second LP over the violation alone says what this box can
  /// remove: the penalty rises at once until the step removes a tenth of it, and where nothing
  /// can be removed the violation is stationary (the rows cannot be met from here). false: the
  /// penalty rises only once the iteration has settled (for comparison).
  bool steering = true;
  /// A step rejected because rows that held at theta break along it first backs off to where
  /// the first of them reaches zero (each row's quadratic through its value, slope and value at
  /// the step's end) instead of halving the box. On with the receding horizon's tolerance; the
  /// open-loop plans (tolerance 1e-12) keep halving: there it led the knee's exchange into a
  /// walk along a curved row that 200 LP steps did not finish.
  bool back_off = false;
};

/// Improves x in place (and the trust radius and the LP basis, kept across exchange rounds).
/// The radius is first raised to the smallest box in which the linearization clears every
/// violated row. `rows_at_theta`, when given, holds rows_at(theta) with its Jacobian, which is then
/// not evaluated again; on return it holds the rows at the returned theta. An exchange round
/// starts where the last ended: only its new points' rows are new (bound_rows.hpp, append_rows).
SequentialLpOutcome solve_by_sequential_lp(const SequentialLpLinearPart& linear, const NonlinearRows& rows_at, Eigen::VectorXd& theta,
                               double& radius, SequentialLpBasis& basis, const SequentialLpSettings& settings = {},
                               BoundRowsAt* rows_at_theta = nullptr);

/// The bound rows of `points` (bound_rows.hpp) for theta: what the bounds of a fixed joint path add.
NonlinearRows bound_rows_of(const FlatOutputMap& flat, const std::vector<BoundPoint>& points, const Eigen::VectorXd& a_min,
                            double margin);

}  // namespace flatsos::planner::detail
