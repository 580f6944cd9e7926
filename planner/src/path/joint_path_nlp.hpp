#pragma once
// The plan and its joint path as one Ipopt problem: minimize the effort cost . theta over z =
// (theta, c) subject to, at the given time points, the reserve and bound rows of PathRows and
// Y >= 0, with the rows' exact Jacobian and the Hessian of their multiplier-weighted sum
// (PathRows::lagrangianHessian). Newton's steps in theta and c together: the curvature the
// reduced-space quasi-Newton method estimates from gradients, here at every iteration.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "path/path_rows.hpp"

namespace flatsos::planner::detail {

/// A primal-dual point of the problem: z, the multipliers of z's bounds and of the rows (Y >= 0
/// per flat output and point, output-major; then PathRows' rows, point-major).
struct JointPathNlpPoint {
  Eigen::VectorXd z, z_lower, z_upper, rows;
  bool hasMultipliers() const { return rows.size() > 0; }
};

struct JointPathNlpOutcome {
  bool solved = false, infeasible = false;
  std::string solver_status, linear_solver;
  int iterations = 0;
  JointPathNlpPoint at;  ///< where Ipopt stopped (z: the start if it never evaluated)
};

/// From `start`: with multipliers (the last round's, for the first `start_points` of `points`),
/// a warm start near the central path; without, a cold start close to z.
JointPathNlpOutcome solve_joint_path_nlp(const SosSetup& setup, const FlatOutputMap& flat, const PathVariables& v,
                                         const std::vector<PathPoint>& points, const Eigen::VectorXd& reserves_N,
                                         const Eigen::VectorXd& a_min, const JointPathNlpPoint& start,
                                         std::size_t start_points, double tolerance, int max_iterations);

}  // namespace flatsos::planner::detail
