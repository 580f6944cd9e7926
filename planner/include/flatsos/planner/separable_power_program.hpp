#pragma once
// The program static optimization solves at each frame of a measured motion:
//   minimize sum_j w_j |x_j|^p   subject to   B x = b,   lower_j <= x_j <= upper_j   (p > 1),
// with few equality rows (one per joint) and many variables (muscles, reserve actuators).
//
// Solved by Newton's method on the dual: for multipliers lambda the minimizing x is explicit,
//   x_j(lambda) = clamp(sign(s_j) (|s_j| / (p w_j))^(1 / (p - 1)), lower_j, upper_j),
//   s = B^T lambda,
// and the concave dual function's gradient is b - B x(lambda). Its Hessian, -B D B^T with
// D = dx/ds on the variables inside their bounds, is a joints x joints matrix. So each
// iteration costs one small Cholesky factorization, and for p = 2 (D constant on each active
// set) the iteration ends exactly once the active set is right. A backtracking line search on the
// dual keeps every other exponent convergent.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <string>

#include <Eigen/Core>

namespace flatsos::planner {

struct SeparablePowerProgram {
  Eigen::MatrixXd B;         ///< rows x variables
  Eigen::VectorXd b;         ///< rows
  Eigen::VectorXd weights;   ///< > 0 per variable
  Eigen::VectorXd lower, upper;  ///< per variable, lower < upper (infinite allowed)
  double exponent = 2.0;     ///< p > 1
};

struct SeparablePowerSolution {
  bool solved = false;
  std::string message;       ///< why not, when not solved
  Eigen::VectorXd x, multipliers;
  double objective = 0.0;
  double residual = 0.0;     ///< max |B x - b|
  int worst_row = -1;        ///< the row of the largest |B x - b| when not solved
  /// Not solved, and proved so: a Farkas certificate y (the dual's direction of growth or its
  /// gradient) with y^T b beyond the most y^T B x reaches over the box. False when not solved:
  /// the iterations ran out without such a proof.
  bool infeasible = false;
  int iterations = 0;
};

/// Throws std::invalid_argument for no rows, inconsistent sizes, weights <= 0, a lower bound not
/// below its upper one, or p <= 1 or not finite. Not solved (with the message) when B x = b has no
/// solution inside the bounds (the dual then grows without bound) or the iterations run out.
/// `tolerance`: on max |B x - b|, relative to max(1, max |b|).
SeparablePowerSolution solve_separable_power_program(const SeparablePowerProgram& program, double tolerance = 1e-10,
                                                     int max_iterations = 100);

}  // namespace flatsos::planner
