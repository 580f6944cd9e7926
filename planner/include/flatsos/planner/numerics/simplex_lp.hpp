#pragma once
// Linear programs by the dual simplex method of COIN-OR Clp (Debian's coinor-libclp-dev), for
// the exchange method's LPs: few variables, many inequality rows, a vertex solution to machine
// precision in a fraction of an interior-point solve, and robust where rows are nearly
// parallel (the points of a rich flat-output basis crowd where constraints are active).
// Same problem and result types as the Ipopt solver in linear_program.hpp.

#include <vector>

#include <Eigen/SparseCore>

#include "flatsos/planner/numerics/linear_program.hpp"

namespace flatsos::planner {

/// Throws std::invalid_argument for inconsistent sizes or NaN data. Status Solved (optimal),
/// Infeasible (primal infeasible) or Failed (dual infeasible: unbounded, or stopped);
/// solver_status names Clp's outcome; iterations counts simplex pivots; row_multipliers are
/// Clp's row duals (>= 0 on active lower bounds of a minimization).
LinearProgramResult solve_linear_program_simplex(const LinearProgram& lp);

/// The same LP with a sparse constraint matrix (large LPs whose rows touch few variables).
struct SparseLinearProgram {
  Eigen::VectorXd cost;
  Eigen::SparseMatrix<double> G;  ///< column-major, as Clp stores it
  Eigen::VectorXd row_lower, row_upper;
  Eigen::VectorXd x_lower, x_upper;
};
LinearProgramResult solve_linear_program_simplex(const SparseLinearProgram& lp);

/// A simplex basis: the status of every variable, then of every row's activity (not Basic: at
/// that bound). Sequences of similar LPs (a sequential LP's steps) restart from the last basis.
enum class BasisStatus : unsigned char { Basic, AtLower, AtUpper };
struct SimplexBasis {
  std::vector<BasisStatus> variables, rows;
};

/// The bounds' sequential LP's last step-LP basis by row identity, kept across its iterations,
/// exchange rounds and receding-horizon periods: each step LP differs from the last by a small
/// move, so it restarts a few pivots from its optimum.
struct SequentialLpBasis;
/// Deprecated: SequentialLpBasis, kept for existing callers.
using SlpBasis = SequentialLpBasis;
struct SequentialLpBasis {
  std::vector<BasisStatus> step;                                     ///< per free coefficient
  std::vector<BasisStatus> bound_row, bound_slack;                   ///< per bound row (point, muscle, row)
  std::vector<std::vector<BasisStatus>> reserve_row, reserve_slack;  ///< per reserve constraint and point
};

/// Starts from `basis` when its sizes match the LP (with as many basic entries as rows; a start
/// with too many or too few is repaired), cold otherwise, and leaves the final basis in it.
LinearProgramResult solve_linear_program_simplex(const SparseLinearProgram& lp, SimplexBasis& basis);
LinearProgramResult solve_linear_program_simplex(const LinearProgram& lp, SimplexBasis& basis);

}  // namespace flatsos::planner
