#include "numerics/ipopt_support.hpp"

#include <algorithm>
#include <atomic>
#include <mutex>
#include <stdexcept>
#include <vector>

#include <IpUtils.hpp>

#include <sys/resource.h>
#include <sys/time.h>

#include <ctime>

#include "numerics/ipopt_dense_kkt.hpp"

namespace {
// false: Ipopt's CPU timers read the monotonic wall clock (the default, see below); true: getrusage,
// as Ipopt's own (benchmarks measure the difference in one run).
std::atomic<bool> ipopt_timers_by_getrusage{false};

double seconds_of(const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); }
}  // namespace

// Ipopt 3.11 times each phase of each iteration (about 30 timers, each Start and End reading
// CpuTime and SysTime, each a getrusage system call). On this project's virtual machines such a
// call costs microseconds: measured, 54 % of a small LP's solve (3.6 ms for 12 iterations, 1.3 ms
// without). Ipopt has no switch for its timers before 3.13, but libipopt calls these two functions
// through its procedure linkage table, so the program's definitions take their place. Inside
// flatsos's own solves (FlatsosSolveScope) they read the monotonic wall clock, counted as CPU time,
// and no system time: nothing in flatsos reads them and no solve depends on them (flatsos sets no
// CPU-time limit). Everywhere else they are Ipopt's own: getrusage's user and system time, so an
// Ipopt problem of another library in the same process keeps its statistics and CPU-time limit.
// They live in this file because every Ipopt solve goes through it, so a static link keeps them.
namespace {
thread_local int flatsos_solves_on_thread = 0;

bool cheap_timers() {
  return flatsos_solves_on_thread > 0 && !ipopt_timers_by_getrusage.load(std::memory_order_relaxed);
}
}  // namespace

namespace Ipopt {
Number CpuTime() {
  if (!cheap_timers()) {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return seconds_of(usage.ru_utime);
  }
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<Number>(now.tv_sec) + 1e-9 * static_cast<Number>(now.tv_nsec);
}
Number SysTime() {
  if (cheap_timers()) return 0.0;
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return seconds_of(usage.ru_stime);
}
}  // namespace Ipopt

namespace flatsos {
namespace planner {
namespace {
std::atomic<IpoptLinearSolver> process_linear_solver{IpoptLinearSolver::Automatic};
}  // namespace

void set_ipopt_timers_by_getrusage(bool by_getrusage) { ipopt_timers_by_getrusage.store(by_getrusage); }

void set_ipopt_linear_solver(IpoptLinearSolver solver) { process_linear_solver.store(solver); }

IpoptLinearSolver ipopt_linear_solver() { return process_linear_solver.load(); }

IpoptLinearSolver ipopt_linear_solver_for(int kkt_dimension, int condensed_dimension) {
  // Condensed only when the pairs are most of the system: a sparse system of mostly equality
  // rows (the collocation's) stays with MUMPS, which wins there from dimension 212 on.
  const bool condensable = condensed_dimension <= kCondensedKktMaxDimension && 4 * condensed_dimension <= kkt_dimension;
  return kkt_dimension <= kDenseKktMaxDimension || condensable ? IpoptLinearSolver::DenseLdlt : IpoptLinearSolver::Mumps;
}

std::string ipopt_linear_solver_name(IpoptLinearSolver solver) {
  switch (solver) {
    case IpoptLinearSolver::DenseLdlt: return "dense LDL^T (flatsos)";
    case IpoptLinearSolver::Mumps: return "MUMPS";
    case IpoptLinearSolver::SparseLdlt: return "sparse LDL^T (flatsos)";
    case IpoptLinearSolver::Automatic: return "automatic";
  }
  return "unknown";
}

void add_linear_solver_name(std::string& names, const std::string& name) {
  if (name.empty()) return;
  std::size_t start = 0;
  while (start <= names.size()) {
    const std::size_t end = std::min(names.find(", ", start), names.size());
    if (names.compare(start, end - start, name) == 0) return;
    start = end + 2;
  }
  names += names.empty() ? name : ", " + name;
}

namespace detail {

FlatsosSolveScope::FlatsosSolveScope(bool holds_dense_kkt_slot, int sparse_primal_rows)
    : holds_slot_(holds_dense_kkt_slot), previous_sparse_primal_rows_(set_sparse_kkt_primal_rows(sparse_primal_rows)) {
  ++flatsos_solves_on_thread;
}

FlatsosSolveScope::FlatsosSolveScope(FlatsosSolveScope&& other) noexcept
    : live_(other.live_), holds_slot_(other.holds_slot_), previous_sparse_primal_rows_(other.previous_sparse_primal_rows_) {
  other.live_ = other.holds_slot_ = false;
}

FlatsosSolveScope::~FlatsosSolveScope() {
  if (!live_) return;
  --flatsos_solves_on_thread;
  set_sparse_kkt_primal_rows(previous_sparse_primal_rows_);
  if (holds_slot_) return_dense_kkt_slot();
}

bool FlatsosSolveScope::active() { return flatsos_solves_on_thread > 0; }

KktDimensions kkt_dimensions(Ipopt::TNLP& problem) {
  Ipopt::Index n = 0, m = 0, nnz_jac = 0, nnz_h = 0;
  Ipopt::TNLP::IndexStyleEnum style = Ipopt::TNLP::C_STYLE;
  if (!problem.get_nlp_info(n, m, nnz_jac, nnz_h, style)) return {};
  std::vector<double> x_lower(static_cast<std::size_t>(n)), x_upper(x_lower.size());
  std::vector<double> g_lower(static_cast<std::size_t>(m)), g_upper(g_lower.size());
  if (!problem.get_bounds_info(n, x_lower.data(), x_upper.data(), m, g_lower.data(), g_upper.data()))
    return {n + 2 * m, n + 2 * m, n + m};
  int equalities = 0;
  for (Ipopt::Index i = 0; i < m; ++i) equalities += g_lower[static_cast<std::size_t>(i)] == g_upper[static_cast<std::size_t>(i)];
  // Ipopt takes fixed variables out of its KKT system (fixed_variable_treatment make_parameter).
  int fixed = 0;
  for (Ipopt::Index i = 0; i < n; ++i) fixed += x_lower[static_cast<std::size_t>(i)] == x_upper[static_cast<std::size_t>(i)];
  return {n + equalities + 2 * (m - equalities), n + equalities, n - fixed + (m - equalities)};
}

IpoptSession make_ipopt(double tol, int max_iter, Ipopt::TNLP& problem, bool rows_in_time_order) {
  static std::recursive_mutex mumps;
  IpoptLinearSolver solver = ipopt_linear_solver();
  const KktDimensions kkt = kkt_dimensions(problem);
  if (solver == IpoptLinearSolver::Automatic)
    solver = rows_in_time_order && kkt.full > kDenseKktMaxDimension ? IpoptLinearSolver::SparseLdlt
                                                                     : ipopt_linear_solver_for(kkt.full, kkt.condensed);
  std::unique_lock<std::recursive_mutex> lock(mumps);
  // flatsos's own LDL^T in the slot Ipopt names ma27 (numerics/ipopt_dense_kkt.hpp), for this
  // session only; MUMPS where the slot holds another MA27.
  const bool own = solver != IpoptLinearSolver::Mumps && claim_dense_kkt_slot();
  if (!own) solver = IpoptLinearSolver::Mumps;
  const int sparse_primal_rows = solver == IpoptLinearSolver::SparseLdlt ? std::max(kkt.primal, 1) : 0;
  IpoptSession session{std::move(lock), FlatsosSolveScope(own, sparse_primal_rows), IpoptApplicationFactory(), solver};
  Ipopt::IpoptApplication* app = Ipopt::GetRawPtr(session.app);
  app->Options()->SetIntegerValue("print_level", 0);
  app->Options()->SetStringValue("sb", "yes");  // no banner
  if (own) {
    app->Options()->SetStringValue("linear_solver", "ma27");
    // Ipopt would ask the HSL loader for MC19 to scale the system; none is loaded.
    app->Options()->SetStringValue("linear_system_scaling", "none");
    // The workspace the solver asks for holds the matrix and its dense factor exactly; Ipopt's
    // default allocates 5 times that.
    app->Options()->SetNumericValue("ma27_la_init_factor", 1.0);
    app->Options()->SetNumericValue("ma27_liw_init_factor", 1.0);
  } else {
    app->Options()->SetStringValue("linear_solver", "mumps");
  }
  app->Options()->SetNumericValue("tol", tol);
  app->Options()->SetIntegerValue("max_iter", max_iter);
  if (app->Initialize("") != Ipopt::Solve_Succeeded)
    throw std::runtime_error("Ipopt failed to initialize");
  return session;
}

std::string ipopt_status_name(Ipopt::ApplicationReturnStatus s) {
  switch (s) {
    case Ipopt::Solve_Succeeded: return "Solve_Succeeded";
    case Ipopt::Solved_To_Acceptable_Level: return "Solved_To_Acceptable_Level";
    case Ipopt::Infeasible_Problem_Detected: return "Infeasible_Problem_Detected";
    case Ipopt::Search_Direction_Becomes_Too_Small: return "Search_Direction_Becomes_Too_Small";
    case Ipopt::Diverging_Iterates: return "Diverging_Iterates";
    case Ipopt::User_Requested_Stop: return "User_Requested_Stop";
    case Ipopt::Feasible_Point_Found: return "Feasible_Point_Found";
    case Ipopt::Maximum_Iterations_Exceeded: return "Maximum_Iterations_Exceeded";
    case Ipopt::Restoration_Failed: return "Restoration_Failed";
    case Ipopt::Error_In_Step_Computation: return "Error_In_Step_Computation";
    case Ipopt::Maximum_CpuTime_Exceeded: return "Maximum_CpuTime_Exceeded";
    case Ipopt::Not_Enough_Degrees_Of_Freedom: return "Not_Enough_Degrees_Of_Freedom";
    case Ipopt::Invalid_Problem_Definition: return "Invalid_Problem_Definition";
    case Ipopt::Invalid_Option: return "Invalid_Option";
    case Ipopt::Invalid_Number_Detected: return "Invalid_Number_Detected";
    default: return "Ipopt_Error_" + std::to_string(static_cast<int>(s));
  }
}

bool ipopt_solved(Ipopt::ApplicationReturnStatus s) {
  return s == Ipopt::Solve_Succeeded || s == Ipopt::Solved_To_Acceptable_Level;
}

bool ipopt_infeasible(Ipopt::ApplicationReturnStatus s) {
  return s == Ipopt::Infeasible_Problem_Detected;
}

}  // namespace detail
}  // namespace planner
}  // namespace flatsos
