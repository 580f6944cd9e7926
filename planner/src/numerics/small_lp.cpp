#include "flatsos/planner/numerics/small_lp.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>

namespace flatsos::planner {

SmallLpResult solve_small_lp(const LinearProgram& lp) {
  const Eigen::Index n = lp.cost.size(), rows = lp.G.rows();
  if (lp.G.cols() != n || lp.row_lower.size() != rows || lp.x_lower.size() != n || lp.x_upper.size() != n)
    throw std::invalid_argument("small LP: inconsistent sizes");
  const auto unbounded = [](const Eigen::VectorXd& v) { return !v.allFinite() || (v.array().abs() >= 1e19).any(); };
  if (unbounded(lp.x_lower) || unbounded(lp.x_upper) || (lp.row_upper.array() < 1e19).any() ||
      !lp.row_lower.allFinite() || !lp.G.allFinite() || !lp.cost.allFinite())
    throw std::invalid_argument("small LP: needs finite data, finite variable bounds and rows G x >= lower only");

  // Primal rows A x >= b: the G rows, then x >= x_lower, then -x >= -x_upper.
  const Eigen::Index m = rows + 2 * n;
  Eigen::MatrixXd A(m, n);
  Eigen::VectorXd b(m);
  A << lp.G, Eigen::MatrixXd::Identity(n, n), -Eigen::MatrixXd::Identity(n, n);
  b << lp.row_lower, lp.x_lower, -lp.x_upper;
  // Scale each row to unit infinity norm: the pivot tolerances are then meaningful.
  for (Eigen::Index i = 0; i < m; ++i) {
    const double s = A.row(i).cwiseAbs().maxCoeff();
    if (s > 0.0) A.row(i) /= s, b[i] /= s;
  }

  // Dual: minimize -b^T y subject to A^T y = c, y >= 0 (n equality rows). Rows with c_k < 0 are
  // negated so that the artificial start basis is feasible.
  Eigen::VectorXd sign = Eigen::VectorXd::Ones(n);
  for (Eigen::Index k = 0; k < n; ++k)
    if (lp.cost[k] < 0.0) sign[k] = -1.0;
  // Columns 0..m-1: y; m..m+n-1: artificials.
  Eigen::MatrixXd M(n, m + n);
  M.leftCols(m) = sign.asDiagonal() * A.transpose();
  M.rightCols(n) = Eigen::MatrixXd::Identity(n, n);
  const Eigen::VectorXd r = sign.cwiseProduct(lp.cost);
  const double scale = 1.0 + r.cwiseAbs().maxCoeff() + b.cwiseAbs().maxCoeff();
  const double eps = 1e-11;

  std::vector<Eigen::Index> basis(static_cast<std::size_t>(n));
  for (Eigen::Index k = 0; k < n; ++k) basis[static_cast<std::size_t>(k)] = m + k;
  SmallLpResult out;

  // One simplex phase with costs f over the allowed columns; false if unbounded.
  auto run = [&](const Eigen::VectorXd& f, Eigen::Index allowed_columns) -> bool {
    for (int guard = 0; guard < 100000; ++guard) {
      Eigen::MatrixXd B(n, n);
      Eigen::VectorXd fB(n);
      for (Eigen::Index k = 0; k < n; ++k) B.col(k) = M.col(basis[static_cast<std::size_t>(k)]), fB[k] = f[basis[static_cast<std::size_t>(k)]];
      const Eigen::PartialPivLU<Eigen::MatrixXd> lu(B);
      const Eigen::VectorXd z = lu.solve(r);                       // basic values
      const Eigen::VectorXd pi = lu.transpose().solve(fB);         // multipliers
      Eigen::Index entering = -1;
      for (Eigen::Index j = 0; j < allowed_columns; ++j) {         // Bland: first improving column
        if (std::find(basis.begin(), basis.end(), j) != basis.end()) continue;
        if (f[j] - pi.dot(M.col(j)) < -eps * scale) {
          entering = j;
          break;
        }
      }
      if (entering < 0) return true;                               // optimal
      const Eigen::VectorXd u = lu.solve(M.col(entering));
      Eigen::Index leave = -1;
      double best = 0.0;
      for (Eigen::Index k = 0; k < n; ++k) {
        if (u[k] <= eps) continue;
        const double ratio = std::max(z[k], 0.0) / u[k];
        if (leave < 0 || ratio < best - eps ||
            (std::abs(ratio - best) <= eps && basis[static_cast<std::size_t>(k)] < basis[static_cast<std::size_t>(leave)]))
          leave = k, best = ratio;
      }
      if (leave < 0) return false;                                 // unbounded direction
      basis[static_cast<std::size_t>(leave)] = entering;
      ++out.pivots;
    }
    throw std::runtime_error("small LP: pivot limit reached");
  };

  // Phase 1: minimize the artificials.
  Eigen::VectorXd f1 = Eigen::VectorXd::Zero(m + n);
  f1.tail(n).setOnes();
  run(f1, m + n);
  {
    Eigen::MatrixXd B(n, n);
    for (Eigen::Index k = 0; k < n; ++k) B.col(k) = M.col(basis[static_cast<std::size_t>(k)]);
    const Eigen::VectorXd z = B.partialPivLu().solve(r);
    double artificial = 0.0;
    for (Eigen::Index k = 0; k < n; ++k)
      if (basis[static_cast<std::size_t>(k)] >= m) artificial += z[k];
    // The box rows make the primal bounded, so the dual is feasible; a residue means round-off.
    if (artificial > 1e-9 * scale) {
      out.status = SolveStatus::Failed;
      return out;
    }
    // Drive degenerate artificials out of the basis.
    for (Eigen::Index k = 0; k < n; ++k) {
      if (basis[static_cast<std::size_t>(k)] < m) continue;
      const Eigen::PartialPivLU<Eigen::MatrixXd> lu(B);
      for (Eigen::Index j = 0; j < m; ++j) {
        if (std::find(basis.begin(), basis.end(), j) != basis.end()) continue;
        if (std::abs(lu.solve(M.col(j))[k]) > 1e-9) {
          basis[static_cast<std::size_t>(k)] = j;
          B.col(k) = M.col(j);
          break;
        }
      }
    }
  }
  // Phase 2: minimize -b^T y over the y columns only.
  Eigen::VectorXd f2 = Eigen::VectorXd::Zero(m + n);
  f2.head(m) = -b;
  f2.tail(n).setConstant(1e30);  // artificials must stay at zero
  if (!run(f2, m)) {
    out.status = SolveStatus::Infeasible;  // dual unbounded: the primal rows are inconsistent
    return out;
  }
  // The primal solution from the optimal basis: the active rows hold with equality.
  Eigen::MatrixXd AB(n, n);
  Eigen::VectorXd bB(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::Index j = basis[static_cast<std::size_t>(k)];
    if (j >= m) {
      out.status = SolveStatus::Failed;
      return out;
    }
    AB.row(k) = A.row(j);
    bB[k] = b[j];
  }
  out.x = AB.fullPivLu().solve(bB);
  out.objective = lp.cost.dot(out.x);
  out.status = (A * out.x - b).minCoeff() >= -1e-8 * scale ? SolveStatus::Solved : SolveStatus::Failed;
  return out;
}

}  // namespace flatsos::planner
