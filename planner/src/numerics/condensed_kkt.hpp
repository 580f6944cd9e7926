#pragma once
// Ipopt's KKT system with its inequality rows eliminated first, for problems with few variables
// and many rows (the joint path's NLP: 218 variables, 6480 rows).
//
// Each inequality row i brings a slack s_i and a multiplier d_i. In Ipopt's augmented system s_i
// couples only to d_i (the block [Sigma_s, -1; -1, -delta_c]), and d_i to the variables through
// row i of the Jacobian. Eliminating every such pair by its own 2x2 block leaves the Schur
// complement over the rest (the core: variables and equality multipliers),
//   S = A - sum_i (P_i^-1)_dd b_i b_i^T,
// dense and small, factored by the dense Bunch-Kaufman LDL^T. The inertia is the pairs' blocks'
// plus S's (Sylvester's law of inertia on the block elimination). The pairs are found from the
// sparsity pattern alone, so any matrix of this shape qualifies.
//
// Like the dense slot (numerics/ipopt_dense_kkt.hpp), the factor lives in caller-owned arrays.

#include <cstdint>
#include <vector>

#include "numerics/dense_ldlt.hpp"

namespace flatsos::planner::detail {

/// Which indices form eliminable pairs. Pair p: an index s with exactly one other index in its
/// row, that index d, and no other pair touching d. Every other index is in the core.
struct CondensedPattern {
  /// Per index: its position in the core (>= 0), or -1 - 2p (pair p's s), or -2 - 2p (pair p's d).
  std::vector<int> role;
  int core = 0, pairs = 0;
  /// Distinct (d, core) index pairs of the pattern: the couplings the factor keeps.
  std::int64_t couplings = 0;
};

/// From 1-based triplets of either triangle (duplicates allowed), as Ipopt's ma27 slot gets them.
/// Indices must be in range (the caller checks).
CondensedPattern find_eliminable_pairs(int n, int nz, const int* irn, const int* icn);

/// Workspace of a condensed factor: integers and reals.
std::int64_t condensed_integer_workspace(const CondensedPattern& p);
std::int64_t condensed_real_workspace(const CondensedPattern& p);

/// Factors the matrix (triplets with `values`, the pattern `p` was found from) into `iw` and
/// `real` (sizes as above), its inertia into `inertia` (zero counts a singular pair block and
/// a zero pivot of S). False, and nothing usable, when the triplets are not p's pattern.
bool factor_condensed(int n, int nz, const int* irn, const int* icn, const double* values, const CondensedPattern& p,
                      int* iw, double* real, Inertia& inertia);

/// Solves with that factor, rhs -> x in place; `scratch` holds the core's length.
void solve_condensed(const int* iw, const double* real, double* rhs, double* scratch);

/// The core's dimension, from a factor (Ipopt's solve scratch is sized by it).
int condensed_core(const int* iw);

}  // namespace flatsos::planner::detail
