#pragma once
// The secondary linear program (SLP, paper section "Linear Programming Solution"): with no
// initial constraints on Y and dY(T) = 0, the optimal Y is a constant alpha solving
//   minimize sum(alpha)  subject to  C_Y alpha >= B,  alpha >= 0,
//   B_j = F_reserve,j - min over the torque box of C_tau,j tau.
// Under Assumption 1, sigma = C_Y 1_p > 0 (paper appendix), so alpha = gamma 1_p with
// gamma = max(max_j B_j / sigma_j, 0) is always feasible. (The paper writes alpha = gamma sigma,
// which has the wrong size: sigma has m entries, alpha p.)

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include "flatsos/planner/numerics/linear_program.hpp"
#include "flatsos/planner/numerics/simplex_lp.hpp"

namespace flatsos::planner {

/// B from a torque box [tau_min, tau_max] (per joint) and the reserves.
Eigen::VectorXd slp_bound_vector(const Eigen::MatrixXd& Ctau, const Eigen::VectorXd& tau_min,
                                 const Eigen::VectorXd& tau_max, const Eigen::VectorXd& reserves_N);
/// The same into `B` (allocates nothing when B already has m entries).
void slp_bound_vector(const Eigen::MatrixXd& Ctau, const Eigen::VectorXd& tau_min, const Eigen::VectorXd& tau_max,
                      const Eigen::VectorXd& reserves_N, Eigen::VectorXd& B);

/// The appendix construction: always feasible, generally not optimal.
Eigen::VectorXd slp_appendix_solution(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B);

/// Exact optimum by enumerating the vertices of {C_Y alpha >= B, alpha >= 0} (p active
/// constraints out of m + p). For small p only (cost grows as C(m + p, p)); reference solver in
/// tests and a fast exact path. Throws std::runtime_error if no vertex is feasible.
Eigen::VectorXd slp_vertex_enumeration(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B);

/// VertexEnumeration: exact, every vertex of the feasible set, allocation-free; the dual simplex
/// solves instead when there would be more than 20000 vertices (C(m + p, p): posture-dependent
/// moment arms stack the rows of every grid posture).
/// Simplex: exact, Clp's dual simplex, restarted from the workspace's last basis (a receding
/// horizon's consecutive SLPs differ little, so few pivots are left); allocates.
/// (slp_study.hpp has Ipopt's interior-point solution as a second opinion.)
enum class SlpSolver { VertexEnumeration, Simplex };

struct SlpResult {
  SolveStatus status = SolveStatus::Failed;
  std::string message;
  Eigen::VectorXd alpha;       ///< the constant flat outputs, N
  double cost_N = 0.0;         ///< c . alpha (SlpWorkspace::cost; sum(alpha) by default)
  bool used_fallback = false;  ///< the solver failed and the appendix construction was used
  int iterations = 0;
  std::string ipopt_linear_solver;  ///< what factored Ipopt's KKT systems (slp_study.hpp; empty otherwise)
  double wall_seconds = 0.0;
};

/// Work storage of solve_slp, reusable across calls of the same size (m x p): with it the exact
/// solver allocates nothing.
struct SlpWorkspace {
  Eigen::MatrixXd rows, active;       ///< [C_Y; I] and the p active rows of one vertex
  Eigen::VectorXd rhs, active_rhs, permuted, vertex, slack, row_sums, start;
  std::vector<Eigen::Index> pick;     ///< indices of the active rows
  /// The cost c of alpha (p entries); empty: sum(alpha), the paper's. Set by the caller (the
  /// receding-horizon step: the effort weights' flat-output part, c = C_Y^T w).
  Eigen::VectorXd cost;
  Eigen::FullPivLU<Eigen::MatrixXd> lu;
  /// The dual simplex's last basis: the next SLP of the same size starts from it.
  SimplexBasis basis;
  /// c . alpha, or sum(alpha) when no cost is set.
  double costOf(const Eigen::VectorXd& alpha) const { return cost.size() ? cost.dot(alpha) : alpha.sum(); }
  /// c itself, or ones(p) when no cost is set (allocates: for building an LP).
  Eigen::VectorXd costVector(Eigen::Index p) const { return cost.size() ? cost : Eigen::VectorXd::Ones(p); }
};

/// Solves the SLP; if the simplex fails, the result falls back to the appendix construction
/// (feasible, status Solved, used_fallback = true, message says why). Throws
/// std::invalid_argument for wrong sizes or NaN, or if some row sum of C_Y is not positive
/// (Assumption 1).
SlpResult solve_slp(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B, SlpSolver solver = SlpSolver::VertexEnumeration);
/// The same into `result`, with reusable work storage (no allocation with VertexEnumeration once
/// both have been used for this size).
void solve_slp(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B, SlpSolver solver, SlpWorkspace& workspace,
               SlpResult& result);

}  // namespace flatsos::planner
