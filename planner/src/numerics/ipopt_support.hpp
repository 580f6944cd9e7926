#pragma once
// Private helpers for the planner's Ipopt problems (C++ TNLP interface only: Simbody's
// libSimTKmath exports Ipopt's C-API symbol names).
#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>

#include <mutex>
#include <string>

#include "flatsos/planner/numerics/ipopt_linear_solver.hpp"

namespace flatsos::planner::detail {

/// An Ipopt application together with the process-wide lock of Debian's sequential MUMPS, which
/// keeps global state (its stand-in MPI layer): two solves at once, or a solver torn down while
/// another runs, abort the process ("PB allocation in DMUMPS_LOAD_INIT", "Instance Error 1 in
/// DMUMPS_F77", measured with two planning threads). The lock is held from creation until the
/// application (and the MUMPS instance inside it) is destroyed; members are destroyed in reverse
/// order, so the application goes first. The same thread may open nested sessions.
/// Marks the calling thread as inside a flatsos solve for as long as it lives: Ipopt's CPU timers
/// then read the cheap monotonic clock (ipopt_support.cpp), and a dense-KKT claim
/// (ipopt_dense_kkt.hpp) it holds is returned when it ends. Outside every such scope both behave
/// as Ipopt's own. Movable, not copyable.
class FlatsosSolveScope {
 public:
  /// sparse_primal_rows > 0: the KKT systems analysed meanwhile go to the sparse LDL^T in time
  /// order with that many primal rows (ipopt_dense_kkt.hpp), the thread's setting restored after.
  explicit FlatsosSolveScope(bool holds_dense_kkt_slot, int sparse_primal_rows = 0);
  FlatsosSolveScope(FlatsosSolveScope&& other) noexcept;
  FlatsosSolveScope& operator=(FlatsosSolveScope&&) = delete;
  FlatsosSolveScope(const FlatsosSolveScope&) = delete;
  ~FlatsosSolveScope();
  /// Whether the calling thread is inside a flatsos solve.
  static bool active();

 private:
  bool live_ = true, holds_slot_ = false;
  int previous_sparse_primal_rows_ = 0;
};

struct IpoptSession {
  std::unique_lock<std::recursive_mutex> lock;
  FlatsosSolveScope scope;  // ends after the application, before the lock
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app;
  IpoptLinearSolver linear_solver = IpoptLinearSolver::Mumps;  ///< the one this application uses
  Ipopt::IpoptApplication* operator->() const { return Ipopt::GetRawPtr(app); }
  Ipopt::IpoptApplication& operator*() const { return *app; }
};

/// A quiet Ipopt application for `problem`. Its linear solver: the process-wide choice
/// (flatsos/planner/numerics/ipopt_linear_solver.hpp), which by default depends on the
/// problem's KKT dimension. Initialize("") so that no stray ipopt.opt in the working directory
/// is read. `rows_in_time_order`: the problem's unknowns and rows come in time order (a
/// collocation's), so that Automatic may give it the sparse LDL^T in time order.
IpoptSession make_ipopt(double tol, int max_iter, Ipopt::TNLP& problem, bool rows_in_time_order = false);

/// Dimensions of the KKT system Ipopt factors for `problem` (read from its sizes and bounds).
struct KktDimensions {
  int full = 0;       ///< variables, a multiplier per equality row, a slack and a multiplier per other row
  int condensed = 0;  ///< variables and a multiplier per equality row (the rest eliminated first)
  int primal = 0;     ///< variables not fixed, a slack per other row (the primal unknowns, first in Ipopt's KKT)
};
KktDimensions kkt_dimensions(Ipopt::TNLP& problem);

/// Ipopt's status as text, for messages.
std::string ipopt_status_name(Ipopt::ApplicationReturnStatus status);

/// Whether the status means a usable optimum (Solve_Succeeded or Solved_To_Acceptable_Level).
bool ipopt_solved(Ipopt::ApplicationReturnStatus status);
/// Whether Ipopt says the problem is infeasible.
bool ipopt_infeasible(Ipopt::ApplicationReturnStatus status);

}  // namespace flatsos::planner::detail
