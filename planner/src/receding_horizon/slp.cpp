#include "flatsos/planner/slp.hpp"
#include "flatsos/planner/slp_study.hpp"

#include <cmath>
#include <vector>
#include <limits>
#include <stdexcept>

#include <Eigen/Dense>

#include "flatsos/plugin/stopwatch.hpp"

namespace flatsos::planner {

namespace {
// Validates sizes, finiteness and Assumption 1's row sums sigma = C_Y 1 > 0 (into `row_sums`).
void check(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B, Eigen::VectorXd& row_sums) {
  if (CY.rows() != B.size() || CY.cols() == 0) throw std::invalid_argument("SLP: C_Y must be m x p with m = size of B");
  if (!CY.allFinite() || !B.allFinite()) throw std::invalid_argument("SLP: NaN or Inf in C_Y or B");
  row_sums.resize(CY.rows());
  row_sums.noalias() = CY.rowwise().sum();
  for (Eigen::Index j = 0; j < row_sums.size(); ++j)
    if (!(row_sums[j] > 0.0))
      throw std::invalid_argument("SLP: row " + std::to_string(j) + " of C_Y sums to " + std::to_string(row_sums[j]) +
                                  " <= 0 (Assumption 1, condition 3)");
}

// The appendix construction gamma 1_p into `alpha` (after check).
void appendix_solution(const Eigen::VectorXd& row_sums, const Eigen::VectorXd& B, Eigen::Index p, Eigen::VectorXd& alpha) {
  const double gamma = std::max((B.array() / row_sums.array()).maxCoeff(), 0.0);
  alpha.setConstant(p, gamma);
}

// Exact optimum by vertex enumeration into `alpha` (after check); false when no vertex is feasible.
constexpr double kMaxEnumeratedVertices = 2e4;

// C(n, k) as a double (large values only need to compare with the limit above).
double vertex_count(Eigen::Index n, Eigen::Index k) {
  double c = 1.0;
  for (Eigen::Index i = 1; i <= k; ++i) c = c * static_cast<double>(n - k + i) / static_cast<double>(i);
  return c;
}

bool vertex_enumeration(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B, SlpWorkspace& w, Eigen::VectorXd& alpha) {
  const Eigen::Index m = CY.rows(), p = CY.cols(), n = m + p;
  // Constraint rows: C_Y alpha >= B, then alpha >= 0.
  w.rows.resize(n, p);
  w.rows.topRows(m) = CY;
  w.rows.bottomRows(p).setIdentity();
  w.rhs.resize(n);
  w.rhs.head(m) = B;
  w.rhs.tail(p).setZero();
  w.active.resize(p, p);
  w.active_rhs.resize(p);
  w.vertex.resize(p);
  w.permuted.resize(p);
  w.slack.resize(n);
  alpha.resize(p);
  const double scale = 1.0 + B.cwiseAbs().maxCoeff();
  double best = std::numeric_limits<double>::infinity();
  // Every choice of p active rows, in lexicographic order (a closed-loop step enumerates
  // C(m + p, p) vertices: 210 for the arm).
  w.pick.resize(static_cast<std::size_t>(p));
  for (Eigen::Index k = 0; k < p; ++k) w.pick[static_cast<std::size_t>(k)] = k;
  while (true) {
    for (Eigen::Index k = 0; k < p; ++k) {
      const Eigen::Index r = w.pick[static_cast<std::size_t>(k)];
      w.active.row(k) = w.rows.row(r);
      w.active_rhs[k] = w.rhs[r];
    }
    w.lu.compute(w.active);
    if (w.lu.isInvertible()) {
      // P A Q = L U: x = Q U^-1 L^-1 P b, in the workspace's vectors (FullPivLU::solve
      // allocates a temporary).
      w.permuted.noalias() = w.lu.permutationP() * w.active_rhs;
      w.lu.matrixLU().triangularView<Eigen::UnitLower>().solveInPlace(w.permuted);
      w.lu.matrixLU().triangularView<Eigen::Upper>().solveInPlace(w.permuted);
      w.vertex.noalias() = w.lu.permutationQ() * w.permuted;
      w.slack.noalias() = w.rows * w.vertex;
      w.slack -= w.rhs;
      const double value = w.costOf(w.vertex);
      if (w.slack.minCoeff() >= -1e-10 * scale && value < best) {
        best = value;
        alpha = w.vertex;
      }
    }
    // Next combination: raise the last index that can still move, reset the ones after it.
    Eigen::Index k = p - 1;
    while (k >= 0 && w.pick[static_cast<std::size_t>(k)] == n - p + k) --k;
    if (k < 0) break;
    ++w.pick[static_cast<std::size_t>(k)];
    for (Eigen::Index l = k + 1; l < p; ++l)
      w.pick[static_cast<std::size_t>(l)] = w.pick[static_cast<std::size_t>(l - 1)] + 1;
  }
  return best < std::numeric_limits<double>::infinity();
}
}  // namespace

Eigen::VectorXd slp_bound_vector(const Eigen::MatrixXd& Ctau, const Eigen::VectorXd& tau_min,
                                 const Eigen::VectorXd& tau_max, const Eigen::VectorXd& reserves) {
  Eigen::VectorXd B;
  slp_bound_vector(Ctau, tau_min, tau_max, reserves, B);
  return B;
}

void slp_bound_vector(const Eigen::MatrixXd& Ctau, const Eigen::VectorXd& tau_min, const Eigen::VectorXd& tau_max,
                      const Eigen::VectorXd& reserves, Eigen::VectorXd& B) {
  if (tau_min.size() != Ctau.cols() || tau_max.size() != Ctau.cols() || reserves.size() != Ctau.rows())
    throw std::invalid_argument("SLP: torque box or reserves of the wrong size");
  if ((tau_max - tau_min).minCoeff() < 0.0) throw std::invalid_argument("SLP: torque box with tau_max < tau_min");
  // min over the box of C_tau,j tau = C_tau,j mid - |C_tau,j| half, per row.
  B.resize(Ctau.rows());
  for (Eigen::Index j = 0; j < Ctau.rows(); ++j) {
    double lowest = 0.0;
    for (Eigen::Index i = 0; i < Ctau.cols(); ++i) {
      const double mid = 0.5 * (tau_min[i] + tau_max[i]), half = 0.5 * (tau_max[i] - tau_min[i]);
      lowest += Ctau(j, i) * mid - std::abs(Ctau(j, i)) * half;
    }
    B[j] = reserves[j] - lowest;
  }
}

Eigen::VectorXd slp_appendix_solution(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B) {
  Eigen::VectorXd row_sums, alpha;
  check(CY, B, row_sums);
  appendix_solution(row_sums, B, CY.cols(), alpha);
  return alpha;
}

Eigen::VectorXd slp_vertex_enumeration(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B) {
  SlpWorkspace w;
  check(CY, B, w.row_sums);
  Eigen::VectorXd alpha;
  if (!vertex_enumeration(CY, B, w, alpha)) throw std::runtime_error("SLP: no feasible vertex (violates Assumption 1?)");
  return alpha;
}

namespace {
// The exact solvers, or Ipopt (`ipopt`) from `warm_start`.
void solve(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B, SlpSolver solver, bool ipopt,
           const std::optional<Eigen::VectorXd>& warm_start, SlpWorkspace& w, SlpResult& r) {
  const Stopwatch wall;
  check(CY, B, w.row_sums);
  appendix_solution(w.row_sums, B, CY.cols(), w.start);
  r.status = SolveStatus::Failed;
  r.message.clear();
  r.used_fallback = false;
  r.iterations = 0;
  r.ipopt_linear_solver.clear();  // a reused result must not name an earlier solve's solver
  // Enumeration visits C(m + p, p) vertices: 210 for the paper's arm, millions for dozens of
  // muscles or stacked grid postures, where the simplex's pivots are far fewer.
  const bool too_many = vertex_count(CY.rows() + CY.cols(), CY.cols()) > kMaxEnumeratedVertices;
  if (!ipopt && solver == SlpSolver::VertexEnumeration && !too_many) {
    if (!vertex_enumeration(CY, B, w, r.alpha)) throw std::runtime_error("SLP: no feasible vertex (violates Assumption 1?)");
    r.status = SolveStatus::Solved;
  } else {
    const Eigen::Index m = CY.rows(), p = CY.cols();
    if (warm_start && (warm_start->size() != p || !warm_start->allFinite()))
      throw std::invalid_argument("SLP: warm start must have " + std::to_string(p) + " finite entries");
    LinearProgram lp;
    lp.cost = w.costVector(p);
    lp.G = CY;
    lp.row_lower = B;
    lp.row_upper = Eigen::VectorXd::Constant(m, 1e19);
    lp.x_lower = Eigen::VectorXd::Zero(p);
    lp.x_upper = Eigen::VectorXd::Constant(p, 1e19);
    LinearProgramResult lr;
    if (ipopt) {
      LinearProgramOptions o;
      o.start = warm_start ? *warm_start : w.start;
      lr = solve_linear_program(lp, o);
    } else {
      lr = solve_linear_program_simplex(lp, w.basis);
    }
    r.iterations = lr.iterations;
    if (ipopt) r.ipopt_linear_solver = lr.linear_solver;
    const double scale = 1.0 + B.cwiseAbs().maxCoeff();
    const bool feasible = lr.x.size() == p && lr.x.allFinite() && lr.x.minCoeff() >= -1e-9 * scale &&
                          (CY * lr.x - B).minCoeff() >= -1e-7 * scale;
    if (lr.status == SolveStatus::Solved && feasible) {
      r.alpha = lr.x.cwiseMax(0.0);
      r.status = SolveStatus::Solved;
    } else {
      r.alpha = w.start;
      r.status = SolveStatus::Solved;
      r.used_fallback = true;
      r.message = std::string(ipopt ? "Ipopt" : "the dual simplex") + " did not solve the SLP (" + lr.solver_status +
                  "); using the always-feasible appendix construction";
    }
  }
  r.cost_N = w.costOf(r.alpha);
  r.wall_seconds = wall.seconds();
}
}  // namespace

SlpResult solve_slp(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B, SlpSolver solver) {
  SlpWorkspace w;
  SlpResult r;
  solve(CY, B, solver, false, std::nullopt, w, r);
  return r;
}

void solve_slp(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B, SlpSolver solver, SlpWorkspace& w, SlpResult& r) {
  solve(CY, B, solver, false, std::nullopt, w, r);
}

SlpResult solve_slp_by_ipopt(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B,
                             const std::optional<Eigen::VectorXd>& warm_start) {
  SlpWorkspace w;
  SlpResult r;
  solve(CY, B, SlpSolver::Simplex, true, warm_start, w, r);
  return r;
}

void solve_slp_by_ipopt(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B,
                        const std::optional<Eigen::VectorXd>& warm_start, SlpWorkspace& w, SlpResult& r) {
  solve(CY, B, SlpSolver::Simplex, true, warm_start, w, r);
}

}  // namespace flatsos::planner
