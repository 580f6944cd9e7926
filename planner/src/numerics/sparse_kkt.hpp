#pragma once
// Ipopt's KKT system of a problem whose variables and rows come in time order (a collocation's:
// the unknowns and rows of each mesh point after the previous point's), factored by a sparse
// LDL^T without pivoting (Eigen's simplicial LDL^T) in an order that keeps it banded and its
// pivots away from zero: the primal indices (Ipopt's variables, then slacks) in their own order,
// each multiplier right after the last primal index its row touches. A multiplier's pivot is then
// the Schur complement of its row on what came before, not the zero (or -delta_c) of its
// diagonal. The inertia is D's signs (Sylvester's law of inertia).
//
// Debian's MUMPS factors the arm's collocation KKT (8818 rows, 3.5 Mflop) in 7.4 ms, nearly all
// of it the multifrontal method's bookkeeping; this order in 1.4 ms with the same inertia.
// Without pivoting a tiny pivot is possible where the order meets a singular leading block: it
// is reported as singular, and Ipopt regularizes (delta_c, delta_w) and factors again.

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <cstdint>
#include <memory>
#include <vector>

namespace flatsos::planner::detail {

/// The permuted matrix's pattern, where each 1-based triplet's value is summed, and the factor of
/// the latest values.
struct SparseKkt {
  int n = 0;
  std::vector<int> rows, columns;     ///< the triplets' pattern it was built from (1-based)
  std::vector<int> destination;       ///< per triplet: its slot in `lower`'s values
  std::vector<int> position;          ///< per original index: its place in the order
  Eigen::SparseMatrix<double> lower;  ///< the permuted matrix's lower triangle
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::NaturalOrdering<int>>
      factor;
  Eigen::VectorXd scratch;
};

/// The order and the symbolic factorization from the triplets' pattern (1-based, indices in
/// range); the first `primal` indices are the primal ones.
std::unique_ptr<SparseKkt> analyse_sparse_kkt(int n, int nz, const int* irn, const int* icn,
                                              int primal);

/// Whether these triplets are the pattern `kkt` was analysed from.
bool same_sparse_pattern(const SparseKkt& kkt, int nz, const int* irn, const int* icn);

/// Factors the values `a` (one per triplet). False when a pivot is zero or not finite (the
/// matrix is treated as singular); otherwise `negative` holds the negative eigenvalues' count.
bool factor_sparse_kkt(SparseKkt& kkt, const double* a, int& negative);

/// Solves in place with the latest factor.
void solve_sparse_kkt(SparseKkt& kkt, double* rhs);

}  // namespace flatsos::planner::detail
