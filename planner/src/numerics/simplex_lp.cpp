#include "flatsos/planner/numerics/simplex_lp.hpp"

#include <cmath>
#include <stdexcept>
#include <vector>

#include <ClpSimplex.hpp>

#include "flatsos/plugin/stopwatch.hpp"

namespace flatsos::planner {

namespace {
const char* clp_status_name(int status) {
  switch (status) {
    case 0: return "optimal";
    case 1: return "primal infeasible";
    case 2: return "dual infeasible (unbounded)";
    case 3: return "stopped on iterations or time";
    case 4: return "stopped due to errors";
    default: return "unknown status";
  }
}
}  // namespace

namespace {

// +-1e19 means "no bound" in our convention; Clp's infinity is COIN_DBL_MAX.
Eigen::VectorXd clp_bounds(const Eigen::VectorXd& v) {
  Eigen::VectorXd out = v;
  for (Eigen::Index i = 0; i < out.size(); ++i)
    if (out[i] >= 1e19) out[i] = COIN_DBL_MAX;
    else if (out[i] <= -1e19) out[i] = -COIN_DBL_MAX;
  return out;
}

void require_consistent(Eigen::Index n, Eigen::Index rows, Eigen::Index g_rows, Eigen::Index g_cols, const Eigen::VectorXd& cost,
                        const Eigen::VectorXd& rl, const Eigen::VectorXd& ru, const Eigen::VectorXd& xl, const Eigen::VectorXd& xu) {
  if (g_cols != n || g_rows != rows || rl.size() != rows || ru.size() != rows || xl.size() != n || xu.size() != n)
    throw std::invalid_argument("simplex LP: inconsistent sizes");
  if (!cost.allFinite() || rl.hasNaN() || ru.hasNaN() || xl.hasNaN() || xu.hasNaN())
    throw std::invalid_argument("simplex LP: NaN or infinite data");
}

// Loads column-major packed data into Clp and solves.
LinearProgramResult solve_packed(Eigen::Index n, Eigen::Index rows, const int* starts, const int* indices,
                                 const double* values, const Eigen::VectorXd& cost, const Eigen::VectorXd& row_lower,
                                 const Eigen::VectorXd& row_upper, const Eigen::VectorXd& x_lower,
                                 const Eigen::VectorXd& x_upper) {
  const Stopwatch wall;
  ClpSimplex model;
  model.setLogLevel(0);
  const Eigen::VectorXd xl = clp_bounds(x_lower), xu = clp_bounds(x_upper);
  const Eigen::VectorXd rl = clp_bounds(row_lower), ru = clp_bounds(row_upper);
  model.loadProblem(static_cast<int>(n), static_cast<int>(rows), starts, indices, values, xl.data(), xu.data(), cost.data(),
                    rl.data(), ru.data());
  // Equilibrium scaling only: with geometric scaling (Clp's default) the dual simplex called
  // feasible exchange LPs infeasible (sum of infeasibilities 1e7 where Ipopt and the primal
  // simplex found a point). An infeasible verdict is confirmed by the primal simplex.
  model.scaling(1);
  // Tighter than Clp's 1e-7: the bounded plans' linearized rows change by 1e-4 per newton, and
  // their penalty magnifies what the LP leaves violated.
  model.setPrimalTolerance(1e-9);
  model.setDualTolerance(1e-9);
  model.dual();
  if (model.status() == 1) model.primal();

  LinearProgramResult r;
  const int status = model.status();
  r.solver_status = clp_status_name(status);
  r.status = status == 0 ? SolveStatus::Solved : status == 1 ? SolveStatus::Infeasible : SolveStatus::Failed;
  r.iterations = model.numberIterations();
  r.x = Eigen::Map<const Eigen::VectorXd>(model.primalColumnSolution(), n);
  r.row_multipliers = Eigen::Map<const Eigen::VectorXd>(model.dualRowSolution(), rows);
  r.objective = cost.dot(r.x);
  r.wall_seconds = wall.seconds();
  return r;
}

}  // namespace

LinearProgramResult solve_linear_program_simplex(const LinearProgram& lp) {
  const Eigen::Index n = lp.cost.size(), rows = lp.G.rows();
  require_consistent(n, rows, lp.G.rows(), lp.G.cols(), lp.cost, lp.row_lower, lp.row_upper, lp.x_lower, lp.x_upper);
  if (!lp.G.allFinite()) throw std::invalid_argument("simplex LP: NaN or infinite data");
  // Column-major packed storage is what Clp wants (column starts, row indices, values).
  std::vector<int> starts(static_cast<std::size_t>(n + 1)), indices;
  std::vector<double> values;
  for (Eigen::Index j = 0; j < n; ++j) {
    starts[static_cast<std::size_t>(j)] = static_cast<int>(values.size());
    for (Eigen::Index i = 0; i < rows; ++i)
      if (lp.G(i, j) != 0.0) {
        indices.push_back(static_cast<int>(i));
        values.push_back(lp.G(i, j));
      }
  }
  starts[static_cast<std::size_t>(n)] = static_cast<int>(values.size());
  return solve_packed(n, rows, starts.data(), indices.data(), values.data(), lp.cost, lp.row_lower, lp.row_upper,
                      lp.x_lower, lp.x_upper);
}

LinearProgramResult solve_linear_program_simplex(const SparseLinearProgram& lp) {
  const Eigen::Index n = lp.cost.size(), rows = lp.G.rows();
  require_consistent(n, rows, lp.G.rows(), lp.G.cols(), lp.cost, lp.row_lower, lp.row_upper, lp.x_lower, lp.x_upper);
  Eigen::SparseMatrix<double> G = lp.G;
  G.makeCompressed();
  for (Eigen::Index k = 0; k < G.nonZeros(); ++k)
    if (!std::isfinite(G.valuePtr()[k])) throw std::invalid_argument("simplex LP: NaN or infinite data");
  return solve_packed(n, rows, G.outerIndexPtr(), G.innerIndexPtr(), G.valuePtr(), lp.cost, lp.row_lower, lp.row_upper,
                      lp.x_lower, lp.x_upper);
}

}  // namespace flatsos::planner
