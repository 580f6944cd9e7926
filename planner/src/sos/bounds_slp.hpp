#pragma once
// Sequential linear programming with a trust region: the default solver of the bounds.
// The cost is linear and the optimum sits where as many constraints are active as there are free
// coefficients, so linearizing the bound rows at theta and solving the LP inside a box
// |d| <= Delta converges like Newton's method near the solution. Every row is elastic (a slack
// priced at `penalty` per unit), which keeps each LP feasible and makes the l1 merit
//   phi(theta) = cost . theta + penalty (sum of bound-row violations + reserve-row violations in N)
// an exact penalty once the penalty exceeds every multiplier; steps are accepted by the ratio of
// actual to predicted merit decrease. Near t = 0 the initial state pins the flat outputs, rows
// move little per newton and their multipliers are large: the penalty grows tenfold whenever the
// iteration settles with rows still violated.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "sos/bound_rows.hpp"

namespace flatsos::planner::detail {

struct SlpOutcome {
  bool converged = false;
  bool rows_violated = false;  // settled at the largest penalty with imposed rows still violated
  int iterations = 0, lp_pivots = 0;
  std::string failure;
};

/// Improves theta in place (and the trust radius, kept across exchange rounds).
SlpOutcome solve_bounds_by_slp(const SosSetup& setup, const FlatOutputMap& flat, const std::vector<BoundPoint>& points,
                               const Eigen::VectorXd& a_min, double reserve_margin_N, Eigen::VectorXd& theta, double& radius,
                               int max_iterations);

}  // namespace flatsos::planner::detail
