#pragma once
// The bounds' NLP for Ipopt (limited-memory Hessian): the second opinion beside the sequential
// LP. Minimize cost . theta subject to the reserves' exchange rows (linear) and the bound rows.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "sos/bound_points.hpp"

namespace flatsos::planner::detail {

struct IpoptBoundsOutcome {
  bool solved = false, infeasible = false;
  std::string solver_status;
  std::string linear_solver;
  Eigen::VectorXd x;  ///< where Ipopt stopped (empty if it never evaluated)
  int iterations = 0;
};

IpoptBoundsOutcome solve_bounds_by_ipopt(const SosSetup& setup, const FlatOutputMap& flat,
                                         const std::vector<BoundPoint>& points, const Eigen::VectorXd& a_min,
                                         const Eigen::VectorXd& start, int max_iterations);

}  // namespace flatsos::planner::detail
