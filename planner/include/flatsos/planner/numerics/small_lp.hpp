#pragma once
// An exact solver for linear programs with few variables and many inequality rows, the shape
// of the SOS program's exchange LPs (4 free coefficients, tens to hundreds of points):
//   minimize c^T x  subject to  G x >= row_lower,  x_lower <= x <= x_upper  (all finite).
// It runs the simplex method (Bland's rule: no cycling) on the dual, which has one equality
// row per variable, so each pivot costs O(n * rows). Microseconds where an Ipopt call costs
// milliseconds; the SOS program uses it inside the exchange loop and lets Ipopt solve the final
// LP, so every reported optimum is Ipopt's (tests compare the two).

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <Eigen/Core>

#include "flatsos/planner/numerics/linear_program.hpp"

namespace flatsos::planner {

struct SmallLpResult {
  SolveStatus status = SolveStatus::Failed;  ///< Infeasible: no x satisfies the rows
  Eigen::VectorXd x;
  double objective = 0.0;
  int pivots = 0;
};

/// Requires finite variable bounds and row upper bounds of +infinity (>= 1e19). Throws
/// std::invalid_argument otherwise.
SmallLpResult solve_small_lp(const LinearProgram& lp);

}  // namespace flatsos::planner
