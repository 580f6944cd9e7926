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

/// What a factorization does from the pattern alone, found once per pattern: where each
/// triplet's value goes in the real workspace (S's lower triangle, a pair's block, a coupling;
/// duplicates to the same place), the factor's integers but S's pivots, and the runs of pairs
/// with the same couplings. Each factorization then only sums values into place (Ipopt factors
/// the same pattern at every iterate: sorting the triplets anew was most of the condensed
/// factorization's time besides the Schur updates).
struct CondensedScatter {
  CondensedPattern pattern;
  std::vector<int> rows, columns;         ///< the triplets' pattern it was built from (1-based)
  std::vector<std::int64_t> destination;  ///< per triplet: its offset in the real workspace
  std::vector<int> integers;              ///< the factor's integer part up to S's pivots
  std::vector<int> run_start;             ///< runs of pairs [run_start[r], run_start[r + 1])
};

/// From the triplets' pattern (1-based, `p` found from it). False when the triplets are not p's
/// pattern.
bool build_condensed_scatter(int n, int nz, const int* irn, const int* icn, const CondensedPattern& p,
                             CondensedScatter& out);

/// Whether these triplets are the pattern the scatter was built from.
bool same_pattern(const CondensedScatter& scatter, int nz, const int* irn, const int* icn);

/// Factors the matrix (the scatter's triplets with `values`) into `iw` and `real` (sizes as
/// above), its inertia into `inertia` (zero counts a singular pair block and a zero pivot of S).
void factor_condensed(const CondensedScatter& scatter, const double* values, int* iw, double* real, Inertia& inertia);

/// Both in one: false, and nothing usable, when the triplets are not p's pattern.
bool factor_condensed(int n, int nz, const int* irn, const int* icn, const double* values, const CondensedPattern& p,
                      int* iw, double* real, Inertia& inertia);

/// Solves with that factor, rhs -> x in place; `scratch` holds the core's length.
void solve_condensed(const int* iw, const double* real, double* rhs, double* scratch);

/// The core's dimension, from a factor (Ipopt's solve scratch is sized by it).
int condensed_core(const int* iw);

}  // namespace flatsos::planner::detail
