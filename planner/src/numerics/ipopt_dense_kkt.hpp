#pragma once
// flatsos's dense LDL^T (numerics/dense_ldlt.hpp) as Ipopt's linear solver for small problems.
//
// Debian's Ipopt 3.11 is built with a loader for the HSL solvers it cannot ship: a program may
// hand it three functions with MA27's calling convention (analyse, factor, solve) and then ask
// for linear_solver "ma27". flatsos serves that slot with its own code; no HSL code is in the
// process. Ipopt's MA27 interface keeps every array between its calls, so the functions hold no
// state: the factor lives in Ipopt's real workspace (after the matrix values), the pivots in
// its integer workspace.

namespace flatsos::planner::detail {

/// Fills Ipopt's ma27 slot with the dense solver, for flatsos's own solves only: the slot is
/// filled while at least one claim is held and emptied when the last is returned, so that an
/// Ipopt problem of another library that asks for ma27 outside flatsos's solves meets Ipopt's own
/// behaviour (it looks for an HSL library). Returns false, leaving the slot alone, when it is
/// already filled by someone else (an HSL library loaded into the process): the caller then uses
/// another linear solver. Callers hold the Ipopt session lock (ipopt_support.hpp), which
/// serializes claims.
bool claim_dense_kkt_slot();
/// Returns a successful claim.
void return_dense_kkt_slot();

/// While set above 0 on a thread, the systems analysed there (above kDenseKktMaxDimension) are
/// factored by the sparse LDL^T in time order (numerics/sparse_kkt.hpp), their first
/// `primal_rows` indices the primal ones (Ipopt's variables and slacks). Returns the previous
/// setting, which the caller restores (FlatsosSolveScope does).
int set_sparse_kkt_primal_rows(int primal_rows);

/// The calls as Ipopt makes them (exposed for tests of the calling convention; Ipopt's Fortran
/// integer is int, checked where they are defined). Indices
/// are 1-based (Fortran); entries of either triangle, duplicates summed. info has 20 entries:
/// info[0] the flag (0 ok, 3 singular, -3/-4 integer/real workspace too small with the size
/// needed in info[1], 1 an index out of range), info[1] the rank after a factorization,
/// info[4]/info[5] the real/integer workspace needed, info[14] the negative eigenvalues.
void dense_kkt_analyse(int* n, int* nz, const int* irn, const int* icn, int* iw, int* liw,
                       int* ikeep, int* iw1, int* nsteps, int* iflag, int* icntl, double* cntl,
                       int* info, double* ops);
void dense_kkt_factor(int* n, int* nz, const int* irn, const int* icn, double* a, int* la, int* iw,
                      int* liw, int* ikeep, int* nsteps, int* maxfrt, int* iw1, int* icntl,
                      double* cntl, int* info);
void dense_kkt_solve(int* n, double* a, int* la, int* iw, int* liw, double* w, int* maxfrt,
                     double* rhs, int* iw1, int* nsteps, int* icntl, double* cntl);
void dense_kkt_defaults(int* icntl, double* cntl);

}  // namespace flatsos::planner::detail
