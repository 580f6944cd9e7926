#include "flatsos/planner/numerics/simplex_lp.hpp"

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

LinearProgramResult solve_linear_program_simplex(const LinearProgram& lp) {
  const Stopwatch wall;
  const Eigen::Index n = lp.cost.size(), rows = lp.G.rows();
  if (lp.G.cols() != n || lp.row_lower.size() != rows || lp.row_upper.size() != rows || lp.x_lower.size() != n ||
      lp.x_upper.size() != n)
    throw std::invalid_argument("simplex LP: inconsistent sizes");
  if (lp.cost.hasNaN() || lp.G.hasNaN() || lp.row_lower.hasNaN() || lp.row_upper.hasNaN() || lp.x_lower.hasNaN() ||
      lp.x_upper.hasNaN() || !lp.cost.allFinite() || !lp.G.allFinite())
    throw std::invalid_argument("simplex LP: NaN or infinite data");

  // Column-major dense storage is what Clp's packed format wants (column starts, row indices).
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

  ClpSimplex model;
  model.setLogLevel(0);
  // +-1e19 means "no bound" in our convention; Clp's infinity is COIN_DBL_MAX.
  auto clp_bounds = [](const Eigen::VectorXd& v) {
    Eigen::VectorXd out = v;
    for (Eigen::Index i = 0; i < out.size(); ++i)
      if (out[i] >= 1e19) out[i] = COIN_DBL_MAX;
      else if (out[i] <= -1e19) out[i] = -COIN_DBL_MAX;
    return out;
  };
  const Eigen::VectorXd xl = clp_bounds(lp.x_lower), xu = clp_bounds(lp.x_upper);
  const Eigen::VectorXd rl = clp_bounds(lp.row_lower), ru = clp_bounds(lp.row_upper);
  model.loadProblem(static_cast<int>(n), static_cast<int>(rows), starts.data(), indices.data(), values.data(), xl.data(),
                    xu.data(), lp.cost.data(), rl.data(), ru.data());
  // Equilibrium scaling only: with geometric scaling (Clp's default) the dual simplex called
  // feasible exchange LPs infeasible (sum of infeasibilities 1e7 where Ipopt and the primal
  // simplex found a point). An infeasible verdict is confirmed by the primal simplex.
  model.scaling(1);
  model.dual();
  if (model.status() == 1) model.primal();
  LinearProgramResult r;
  const int status = model.status();
  r.solver_status = clp_status_name(status);
  r.status = status == 0 ? SolveStatus::Solved : status == 1 ? SolveStatus::Infeasible : SolveStatus::Failed;
  r.iterations = model.numberIterations();
  r.x = Eigen::Map<const Eigen::VectorXd>(model.primalColumnSolution(), n);
  r.row_multipliers = Eigen::Map<const Eigen::VectorXd>(model.dualRowSolution(), rows);
  r.objective = lp.cost.dot(r.x);
  r.wall_seconds = wall.seconds();
  return r;
}

}  // namespace flatsos::planner
