#include "sos/sos_exchange.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "flatsos/planner/numerics/ipopt_linear_solver.hpp"
#include "flatsos/planner/numerics/simplex_lp.hpp"
#include "flatsos/plugin/stopwatch.hpp"

namespace flatsos::planner::detail {

bool solve_by_exchange(SosSetup& setup, const SosSettings& o, Eigen::VectorXd& theta, SosProgramResult& result,
                       SequentialLpBasis* final_basis, double tolerance_N) {
  const Stopwatch solve;
  auto& constraints = setup.constraints;
  const LinearProgram& lp = setup.lp;
  const int n_theta = setup.free_coefficients;

  auto build_rows = [&]() { result.lp_points = build_exchange_rows(setup, o.feasibility_margin_N); };

  if (const std::string reason = fixed_violation(setup, o.feasibility_margin_N); !reason.empty()) {
    result.status = SolveStatus::Infeasible;
    result.message = reason;
    result.solve_seconds = solve.seconds();
    return false;
  }
  theta = Eigen::VectorXd::Zero(n_theta);
  bool converged = false;
  // Each round's LP starts from the last one's basis: a point's row keeps its status while it
  // stays (rows follow the constraints' points in order), new points start inactive.
  std::vector<BasisStatus> theta_status(static_cast<std::size_t>(n_theta), BasisStatus::AtLower);
  std::vector<std::vector<BasisStatus>> point_status(constraints.size());
  if (final_basis && final_basis->step.size() == theta_status.size() && final_basis->reserve_row.size() == constraints.size()) {
    // A second call goes on from the first one's basis (points it added since start inactive).
    theta_status = final_basis->step;
    point_status = final_basis->reserve_row;
  }
  auto solve_round = [&](int round) -> bool {
    LinearProgramResult lr;
    if (o.exchange.lp_solver == ExchangeLpSolver::Simplex) {
      SimplexBasis basis{theta_status, {}};
      for (std::size_t c = 0; c < constraints.size(); ++c) {
        point_status[c].resize(constraints[c].points.size(), BasisStatus::Basic);
        basis.rows.insert(basis.rows.end(), point_status[c].begin(), point_status[c].end());
      }
      lr = solve_linear_program_simplex(lp, basis);
      result.simplex_pivots += lr.iterations;
      theta_status = basis.variables;
      auto row = basis.rows.begin();
      for (auto& statuses : point_status)
        for (auto& status : statuses) status = *row++;
    } else {
      LinearProgramOptions lpo;
      if (round > 0) lpo.start = theta;
      lr = solve_linear_program(lp, lpo);
      result.ipopt_iterations += lr.iterations;
      ++result.ipopt_calls;
      add_linear_solver_name(result.ipopt_linear_solver, lr.linear_solver);
    }
    if (lr.status != SolveStatus::Solved) {
      const std::string reason = fixed_violation(setup, o.feasibility_margin_N);
      result.status = lr.status == SolveStatus::Infeasible || !reason.empty() ? SolveStatus::Infeasible : SolveStatus::Failed;
      result.message = !reason.empty() ? reason
                                       : "the exchange LP of round " + std::to_string(round + 1) + " was not solved (" +
                                             (o.exchange.lp_solver == ExchangeLpSolver::Simplex ? "Clp: " : "Ipopt: ") +
                                             lr.solver_status + ")";
      result.solve_seconds = solve.seconds();
      return false;
    }
    theta = lr.x;
    return true;
  };
  for (int round = 0; round < o.max_exchange_rounds; ++round) {
    result.exchange_rounds = round + 1;
    if (n_theta > 0) {
      build_rows();
      if (!solve_round(round)) return false;
      // Keep the LPs small: initial points far from active leave the next LP. A pruned
      // constraint that becomes violated is caught by the exact minimum below and comes back
      // as a sticky point.
      for (std::size_t k = 0; k < constraints.size(); ++k) {
        auto& c = constraints[k];
        auto& statuses = point_status[k];
        statuses.resize(c.points.size(), BasisStatus::Basic);
        const Polynomial g = c.at(theta);
        for (std::size_t i = c.points.size(); i-- > 0;)
          if (!c.sticky[i] && g(c.points[i]) > o.exchange.prune_slack_N) {
            c.points.erase(c.points.begin() + static_cast<std::ptrdiff_t>(i));
            c.sticky.erase(c.sticky.begin() + static_cast<std::ptrdiff_t>(i));
            statuses.erase(statuses.begin() + static_cast<std::ptrdiff_t>(i));
          }
      }
    }
    if (add_violated_points(setup, theta, o.feasibility_margin_N, result.min_constraint_value_N, tolerance_N)) continue;
    converged = true;
    break;
  }
  result.solve_seconds = solve.seconds();
  if (final_basis) {
    final_basis->step = theta_status;
    final_basis->reserve_row = point_status;
    final_basis->reserve_slack.assign(point_status.size(), {});
  }

  if (const std::string reason = fixed_violation(setup, o.feasibility_margin_N); !reason.empty()) {
    result.status = SolveStatus::Infeasible;
    result.message = reason;
    return false;
  }
  if (!converged || result.min_constraint_value_N < -std::max(1e-6, tolerance_N)) {
    result.status = SolveStatus::Failed;
    std::ostringstream why;
    why << "the exchange method did not converge in " << o.max_exchange_rounds << " rounds (worst constraint value "
        << result.min_constraint_value_N << " N)";
    result.message = why.str();
    return false;
  }
  if (n_theta > 0 && (theta.cwiseAbs().maxCoeff() > 0.999 * o.exchange.coefficient_bound_N)) {
    result.status = SolveStatus::Failed;
    result.message = "the SOS program is unbounded: a free coefficient of Y reached the bound " +
                     std::to_string(o.exchange.coefficient_bound_N) + " N";
    return false;
  }

  return true;
}

}  // namespace flatsos::planner::detail
