#include "flatsos/planner/slp.hpp"

#include <cmath>
#include <vector>
#include <limits>
#include <stdexcept>

#include <Eigen/Dense>

#include "flatsos/plugin/stopwatch.hpp"

namespace flatsos::planner {

namespace {
void check(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B) {
  if (CY.rows() != B.size() || CY.cols() == 0) throw std::invalid_argument("SLP: C_Y must be m x p with m = size of B");
  if (!CY.allFinite() || !B.allFinite()) throw std::invalid_argument("SLP: NaN or Inf in C_Y or B");
  const Eigen::VectorXd sigma = CY.rowwise().sum();
  for (Eigen::Index j = 0; j < sigma.size(); ++j)
    if (!(sigma[j] > 0.0))
      throw std::invalid_argument("SLP: row " + std::to_string(j) + " of C_Y sums to " + std::to_string(sigma[j]) +
                                  " <= 0 (Assumption 1, condition 3)");
}
}  // namespace

Eigen::VectorXd slp_bound_vector(const Eigen::MatrixXd& Ctau, const Eigen::VectorXd& tau_min,
                                 const Eigen::VectorXd& tau_max, const Eigen::VectorXd& reserves) {
  if (tau_min.size() != Ctau.cols() || tau_max.size() != Ctau.cols() || reserves.size() != Ctau.rows())
    throw std::invalid_argument("SLP: torque box or reserves of the wrong size");
  if ((tau_max - tau_min).minCoeff() < 0.0) throw std::invalid_argument("SLP: torque box with tau_max < tau_min");
  const Eigen::VectorXd mid = 0.5 * (tau_min + tau_max), half = 0.5 * (tau_max - tau_min);
  return reserves - (Ctau * mid - Ctau.cwiseAbs() * half);
}

Eigen::VectorXd slp_appendix_solution(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B) {
  check(CY, B);
  const Eigen::VectorXd sigma = CY.rowwise().sum();
  const double gamma = std::max((B.array() / sigma.array()).maxCoeff(), 0.0);
  return Eigen::VectorXd::Constant(CY.cols(), gamma);
}

Eigen::VectorXd slp_vertex_enumeration(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B) {
  check(CY, B);
  const Eigen::Index m = CY.rows(), p = CY.cols(), n = m + p;
  // Constraint rows: C_Y alpha >= B, then alpha >= 0.
  Eigen::MatrixXd rows(n, p);
  rows << CY, Eigen::MatrixXd::Identity(p, p);
  Eigen::VectorXd rhs(n);
  rhs << B, Eigen::VectorXd::Zero(p);
  const double scale = 1.0 + B.cwiseAbs().maxCoeff();
  double best = std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_alpha;
  // Every choice of p active rows, in lexicographic order, with the work matrices allocated once
  // (a closed-loop step enumerates C(m + p, p) vertices: 210 for the arm).
  std::vector<Eigen::Index> pick(static_cast<std::size_t>(p));
  for (Eigen::Index k = 0; k < p; ++k) pick[static_cast<std::size_t>(k)] = k;
  Eigen::MatrixXd M(p, p);
  Eigen::VectorXd b(p), alpha(p), slack(n);
  Eigen::FullPivLU<Eigen::MatrixXd> lu(p, p);
  while (true) {
    for (Eigen::Index k = 0; k < p; ++k) {
      const Eigen::Index r = pick[static_cast<std::size_t>(k)];
      M.row(k) = rows.row(r);
      b[k] = rhs[r];
    }
    lu.compute(M);
    if (lu.isInvertible()) {
      alpha.noalias() = lu.solve(b);
      slack.noalias() = rows * alpha;
      slack -= rhs;
      if (slack.minCoeff() >= -1e-10 * scale && alpha.sum() < best) {
        best = alpha.sum();
        best_alpha = alpha;
      }
    }
    // Next combination: raise the last index that can still move, reset the ones after it.
    Eigen::Index k = p - 1;
    while (k >= 0 && pick[static_cast<std::size_t>(k)] == n - p + k) --k;
    if (k < 0) break;
    ++pick[static_cast<std::size_t>(k)];
    for (Eigen::Index l = k + 1; l < p; ++l) pick[static_cast<std::size_t>(l)] = pick[static_cast<std::size_t>(l - 1)] + 1;
  }
  if (best_alpha.size() == 0) throw std::runtime_error("SLP: no feasible vertex (violates Assumption 1?)");
  return best_alpha;
}

SlpResult solve_slp(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B, SlpSolver solver,
                    const std::optional<Eigen::VectorXd>& warm_start) {
  const Stopwatch wall;
  const Eigen::VectorXd start = slp_appendix_solution(CY, B);  // also validates
  SlpResult r;
  if (solver == SlpSolver::VertexEnumeration) {
    r.alpha = slp_vertex_enumeration(CY, B);
    r.status = SolveStatus::Solved;
  } else {
    LinearProgram lp;
    const Eigen::Index m = CY.rows(), p = CY.cols();
    lp.cost = Eigen::VectorXd::Ones(p);
    lp.G = CY;
    lp.row_lower = B;
    lp.row_upper = Eigen::VectorXd::Constant(m, 1e19);
    lp.x_lower = Eigen::VectorXd::Zero(p);
    lp.x_upper = Eigen::VectorXd::Constant(p, 1e19);
    if (warm_start && (warm_start->size() != p || !warm_start->allFinite()))
      throw std::invalid_argument("SLP: warm start must have " + std::to_string(p) + " finite entries");
    LinearProgramOptions o;
    o.start = warm_start ? *warm_start : start;
    const LinearProgramResult lr = solve_linear_program(lp, o);
    r.iterations = lr.iterations;
    const double scale = 1.0 + B.cwiseAbs().maxCoeff();
    const bool feasible = lr.x.size() == p && lr.x.allFinite() && lr.x.minCoeff() >= -1e-9 * scale &&
                          (CY * lr.x - B).minCoeff() >= -1e-7 * scale;
    if (lr.status == SolveStatus::Solved && feasible) {
      r.alpha = lr.x.cwiseMax(0.0);
      r.status = SolveStatus::Solved;
    } else {
      r.alpha = start;
      r.status = SolveStatus::Solved;
      r.used_fallback = true;
      r.message = "Ipopt did not solve the SLP (" + lr.solver_status + "); using the always-feasible appendix construction";
    }
  }
  r.cost_N = r.alpha.sum();
  r.wall_seconds = wall.seconds();
  return r;
}

}  // namespace flatsos::planner
