#pragma once
// Which linear solver factors the KKT systems of the planner's Ipopt problems.
//
// Ipopt spends most of a small problem's time in its linear solver's fixed costs: Debian's MUMPS
// costs 0.3-0.6 ms per iteration whatever the size. flatsos therefore factors small KKT systems
// with its own dense Bunch-Kaufman LDL^T, and a collocation's banded ones with its own sparse
// LDL^T in time order (both served through Ipopt's ma27 slot for the length of its own solves;
// no HSL code is used), and leaves the other large ones to MUMPS.

#include <string>

namespace flatsos::planner {

enum class IpoptLinearSolver {
  /// The dense LDL^T up to kDenseKktMaxDimension, or when the condensed system is at most
  /// kCondensedKktMaxDimension and a quarter of the whole; above that the sparse LDL^T in time
  /// order for problems whose unknowns and rows come in time order (the collocation's); MUMPS
  /// otherwise (the default).
  Automatic,
  /// flatsos's dense Bunch-Kaufman LDL^T, whatever the size. Above kDenseKktMaxDimension it
  /// first eliminates each inequality row's slack and multiplier by their own 2x2 block and
  /// factors the dense rest (the condensed system: variables and equality rows).
  DenseLdlt,
  Mumps,  ///< MUMPS (sparse multifrontal), whatever the size
  /// flatsos's sparse LDL^T in time order (numerics/sparse_kkt.hpp): each multiplier after the
  /// last variable its row touches. Automatic picks it above kDenseKktMaxDimension for the
  /// problems whose unknowns and rows come in time order (the collocation reference's).
  SparseLdlt,
};

/// Largest KKT dimension (variables + equality rows + 2 x inequality rows) that Automatic gives
/// to the dense LDL^T: where, measured per Ipopt iteration on this project's problems, the two
/// cost the same (docs/method/ipopt_linear_solver.md).
inline constexpr int kDenseKktMaxDimension = 200;
/// Largest condensed dimension (variables + equality rows) that Automatic gives to the dense
/// LDL^T with the inequality rows eliminated first, when that is at most a quarter of the KKT
/// dimension (docs/method/ipopt_linear_solver.md).
inline constexpr int kCondensedKktMaxDimension = 400;

/// Process-wide choice for every later Ipopt solve (tests and benchmarks compare the two;
/// thread-safe, a solve already running keeps its solver).
void set_ipopt_linear_solver(IpoptLinearSolver solver);
IpoptLinearSolver ipopt_linear_solver();

/// The solver Automatic picks for a KKT system of this dimension whose condensed system (without
/// the inequality rows' slacks and multipliers) has `condensed_dimension` (the others pick
/// themselves).
IpoptLinearSolver ipopt_linear_solver_for(int kkt_dimension, int condensed_dimension);

/// Name for logs and summaries: "dense LDL^T (flatsos)", "sparse LDL^T (flatsos)" or "MUMPS"
/// ("automatic" for Automatic).
std::string ipopt_linear_solver_name(IpoptLinearSolver solver);

/// Ipopt 3.11 reads its CPU timers (getrusage, about 120 system calls per iteration) whether or
/// not anyone looks at them. Inside flatsos's own solves they read the monotonic wall clock
/// (elsewhere in the process they stay Ipopt's own; docs/method/ipopt_linear_solver.md); `true`
/// restores getrusage inside them too (benchmarks measure the difference in one run). Thread-safe.
void set_ipopt_timers_by_getrusage(bool by_getrusage);

/// Appends `name` to the comma-separated list `names` unless it is there (results that gather
/// several Ipopt calls report every linear solver that served them).
void add_linear_solver_name(std::string& names, const std::string& name);

}  // namespace flatsos::planner
