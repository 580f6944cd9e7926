#pragma once
// A dense symmetric-indefinite factorization written for flatsos: P A P^T = L D L^T with
// Bunch-Kaufman diagonal pivoting (D has 1x1 and 2x2 blocks, L is unit lower triangular, P a
// product of row interchanges), and the inertia of A read off D. It serves the KKT systems of
// Ipopt's small problems (numerics/ipopt_dense_kkt.hpp), where a dense factorization of a few
// hundred rows costs less than a sparse solver's bookkeeping.
//
// The raw functions work in place on a column-major n x n buffer, because Ipopt owns the memory
// that holds the factor between its calls; DenseLdlt owns its own.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <vector>

#include <Eigen/Core>

namespace flatsos::planner::detail {

/// Signs of a symmetric matrix's eigenvalues (Sylvester: those of D).
struct Inertia {
  int positive = 0, negative = 0, zero = 0;
};

/// Factors the lower triangle of the column-major n x n matrix `a` in place (the strict upper
/// triangle is neither read nor written). On return the lower triangle holds L below the
/// diagonal and D on it (a 2x2 block's off-diagonal entry sits below its first diagonal entry,
/// where L has its implicit 0), and `pivots` (n entries) the interchanges:
///   pivots[k] = r >= 0:             a 1x1 block at k, rows k and r interchanged first;
///   pivots[k] = pivots[k+1] = -r-1: a 2x2 block at k, k+1, rows k+1 and r interchanged first.
/// A column whose largest entry is at most `zero_pivot` (absolute) is a zero pivot: D gets an
/// exact 0 there, the inertia counts it as zero, and the solve sets that component to 0.
Inertia factor_ldlt_in_place(double* a, int n, int* pivots, double zero_pivot);

/// Solves A x = b in place (b -> x) with a factor from factor_ldlt_in_place.
void solve_ldlt_in_place(const double* factor, int n, const int* pivots, double* b);

/// Owning form, for callers that hold the matrix themselves.
class DenseLdlt {
 public:
  /// Factors the lower triangle of `a` (square). zero_pivot as above.
  explicit DenseLdlt(const Eigen::MatrixXd& a, double zero_pivot = 0.0);
  const Inertia& inertia() const { return inertia_; }
  int rank() const { return n_ - inertia_.zero; }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;

 private:
  int n_;
  Eigen::MatrixXd factor_;
  std::vector<int> pivots_;
  Inertia inertia_;
};

}  // namespace flatsos::planner::detail
