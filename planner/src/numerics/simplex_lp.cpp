#include "flatsos/planner/numerics/simplex_lp.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
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

constexpr double kMaxClpCost = 1e20;

void require_consistent(Eigen::Index n, Eigen::Index rows, Eigen::Index g_rows, Eigen::Index g_cols, const Eigen::VectorXd& cost,
                        const Eigen::VectorXd& rl, const Eigen::VectorXd& ru, const Eigen::VectorXd& xl, const Eigen::VectorXd& xu) {
  if (g_cols != n || g_rows != rows || rl.size() != rows || ru.size() != rows || xl.size() != n || xu.size() != n)
    throw std::invalid_argument("simplex LP: inconsistent sizes");
  if (!cost.allFinite() || rl.hasNaN() || ru.hasNaN() || xl.hasNaN() || xu.hasNaN())
    throw std::invalid_argument("simplex LP: NaN or infinite data");
  // Clp aborts the process (an assertion) on a cost of 1e25 or more.
  if (cost.size() > 0 && cost.cwiseAbs().maxCoeff() >= kMaxClpCost)
    throw std::invalid_argument("simplex LP: a cost of " + std::to_string(cost.cwiseAbs().maxCoeff()) +
                                " is beyond the solver's range (1e20): the problem's scale (its duration, "
                                "forces or weights) is out of range");
}

unsigned char clp_status(BasisStatus s) {
  switch (s) {
    case BasisStatus::Basic: return ClpSimplex::basic;
    case BasisStatus::AtUpper: return ClpSimplex::atUpperBound;
    case BasisStatus::AtLower: break;
  }
  return ClpSimplex::atLowerBound;
}

BasisStatus basis_status(unsigned char clp) {
  switch (clp & 7) {
    case ClpSimplex::basic: return BasisStatus::Basic;
    case ClpSimplex::atUpperBound: return BasisStatus::AtUpper;
    default: return BasisStatus::AtLower;  // at lower, fixed, or a free nonbasic at 0
  }
}

// Loads a start basis into Clp, with exactly as many basic entries as rows: surplus basic
// variables leave (they sit at a bound, which the dual simplex repairs), missing ones are made
// up by row activities (their rows simply become inactive).
void load_basis(ClpSimplex& model, const SimplexBasis& basis) {
  const int n = model.numberColumns(), rows = model.numberRows();
  std::vector<unsigned char> status(static_cast<std::size_t>(n + rows));
  int basic = 0;
  for (int j = 0; j < n; ++j) basic += (status[static_cast<std::size_t>(j)] = clp_status(basis.variables[static_cast<std::size_t>(j)])) == ClpSimplex::basic;
  for (int i = 0; i < rows; ++i)
    basic += (status[static_cast<std::size_t>(n + i)] = clp_status(basis.rows[static_cast<std::size_t>(i)])) == ClpSimplex::basic;
  for (int k = n + rows - 1; k >= 0 && basic > rows; --k)
    if (status[static_cast<std::size_t>(k)] == ClpSimplex::basic) {
      status[static_cast<std::size_t>(k)] = ClpSimplex::atLowerBound;
      --basic;
    }
  for (int i = rows - 1; i >= 0 && basic < rows; --i)
    if (status[static_cast<std::size_t>(n + i)] != ClpSimplex::basic) {
      status[static_cast<std::size_t>(n + i)] = ClpSimplex::basic;
      ++basic;
    }
  model.copyinStatus(status.data());
}

// Loads column-major packed data into Clp and solves (from `basis` when it fits the LP).
LinearProgramResult solve_packed(Eigen::Index n, Eigen::Index rows, const int* starts, const int* indices,
                                 const double* values, const Eigen::VectorXd& cost, const Eigen::VectorXd& row_lower,
                                 const Eigen::VectorXd& row_upper, const Eigen::VectorXd& x_lower,
                                 const Eigen::VectorXd& x_upper, SimplexBasis* basis) {
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
  // their penalty magnifies what the LP leaves violated. Clp applies them to the scaled problem:
  // unscaled rows hold to about 5e-7 of their size (tested), which the bounds' margin covers.
  model.setPrimalTolerance(1e-9);
  model.setDualTolerance(1e-9);
  if (basis && basis->variables.size() == static_cast<std::size_t>(n) && basis->rows.size() == static_cast<std::size_t>(rows))
    load_basis(model, *basis);
  model.dual();
  if (model.status() == 1) model.primal();
  // Optimal scaled but not unscaled (secondary status 2-4): on the bounds' step LPs the
  // "solution" then had elastic slacks at -5e-4 and steps outside their box. The primal simplex
  // from the basis reached (still scaled) finishes it in a few pivots; unscaled, it called
  // feasible LPs infeasible.
  int pivots = model.numberIterations();
  if (model.status() == 0 && model.secondaryStatus() >= 2 && model.secondaryStatus() <= 4) {
    model.primal();
    pivots += model.numberIterations();
  }
  LinearProgramResult r;
  const int status = model.status();
  r.solver_status = clp_status_name(status);
  r.status = status == 0 ? SolveStatus::Solved : status == 1 ? SolveStatus::Infeasible : SolveStatus::Failed;
  r.iterations = pivots;
  r.x = Eigen::Map<const Eigen::VectorXd>(model.primalColumnSolution(), n);
  r.row_multipliers = Eigen::Map<const Eigen::VectorXd>(model.dualRowSolution(), rows);
  r.objective = cost.dot(r.x);
  if (basis) {
    const unsigned char* final_status = model.statusArray();
    basis->variables.resize(static_cast<std::size_t>(n));
    basis->rows.resize(static_cast<std::size_t>(rows));
    for (Eigen::Index j = 0; j < n; ++j) basis->variables[static_cast<std::size_t>(j)] = basis_status(final_status[j]);
    for (Eigen::Index i = 0; i < rows; ++i) basis->rows[static_cast<std::size_t>(i)] = basis_status(final_status[n + i]);
  }
  r.wall_seconds = wall.seconds();
  return r;
}

LinearProgramResult solve_sparse(const SparseLinearProgram& lp, SimplexBasis* basis) {
  const Eigen::Index n = lp.cost.size(), rows = lp.G.rows();
  require_consistent(n, rows, lp.G.rows(), lp.G.cols(), lp.cost, lp.row_lower, lp.row_upper, lp.x_lower, lp.x_upper);
  Eigen::SparseMatrix<double> G = lp.G;
  G.makeCompressed();
  for (Eigen::Index k = 0; k < G.nonZeros(); ++k)
    if (!std::isfinite(G.valuePtr()[k])) throw std::invalid_argument("simplex LP: NaN or infinite data");
  return solve_packed(n, rows, G.outerIndexPtr(), G.innerIndexPtr(), G.valuePtr(), lp.cost, lp.row_lower, lp.row_upper,
                      lp.x_lower, lp.x_upper, basis);
}

LinearProgramResult solve_dense(const LinearProgram& lp, SimplexBasis* basis) {
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
                      lp.x_lower, lp.x_upper, basis);
}
}  // namespace

LinearProgramResult solve_linear_program_simplex(const LinearProgram& lp) { return solve_dense(lp, nullptr); }

LinearProgramResult solve_linear_program_simplex(const LinearProgram& lp, SimplexBasis& basis) {
  return solve_dense(lp, &basis);
}

LinearProgramResult solve_linear_program_simplex(const SparseLinearProgram& lp) { return solve_sparse(lp, nullptr); }

LinearProgramResult solve_linear_program_simplex(const SparseLinearProgram& lp, SimplexBasis& basis) {
  return solve_sparse(lp, &basis);
}

}  // namespace flatsos::planner
