#pragma once
// Small dense linear programs solved with Ipopt (TNLP interface, constant Jacobian, zero
// Hessian):  minimize c^T x  subject to  row_lower <= G x <= row_upper,  x_lower <= x <= x_upper.
// Infinite bounds are +-1e19 (Ipopt's convention for "none").

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <optional>
#include <string>

#include <Eigen/Core>

#include "flatsos/planner/solve_status.hpp"

namespace flatsos::planner {

struct LinearProgram {
  Eigen::VectorXd cost;
  Eigen::MatrixXd G;
  Eigen::VectorXd row_lower, row_upper;
  Eigen::VectorXd x_lower, x_upper;
};

struct LinearProgramResult {
  SolveStatus status = SolveStatus::Failed;
  std::string solver_status;  ///< Ipopt's return status
  std::string linear_solver;  ///< what factored Ipopt's KKT systems (empty for the simplex)
  Eigen::VectorXd x;
  Eigen::VectorXd row_multipliers;  ///< Ipopt's lambda (>= 0 on active lower bounds here: sign per Ipopt)
  double objective = 0.0;
  int iterations = 0;
  double wall_seconds = 0.0;
};

struct LinearProgramOptions {
  double tolerance = 1e-10;
  int max_iterations = 500;
  std::optional<Eigen::VectorXd> start;  ///< initial x (default: 0 pushed inside the bounds)
};

/// Throws std::invalid_argument for inconsistent sizes or NaN data.
LinearProgramResult solve_linear_program(const LinearProgram& lp, const LinearProgramOptions& options = {});

}  // namespace flatsos::planner
