#include "sos/sos_exchange.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "flatsos/planner/numerics/ipopt_linear_solver.hpp"
#include "flatsos/planner/numerics/simplex_lp.hpp"
#include "flatsos/plugin/stopwatch.hpp"

namespace flatsos::planner::detail {

namespace {

// The exchange LPs' basis: each round's LP starts from the last one's. A point's row keeps its
// status while it stays (rows follow the constraints' points in order), new points start inactive.
struct ExchangeBasis {
  std::vector<BasisStatus> theta;
  std::vector<std::vector<BasisStatus>> points;  // per constraint and point
};

// The LP at the constraints' points; false with result's status and message when not solved.
bool solve_round(const SosSetup& setup, const SosSettings& o, int round, ExchangeBasis& basis, Eigen::VectorXd& theta,
                 SosProgramResult& result) {
  const auto& constraints = setup.constraints;
  LinearProgramResult lr;
  if (o.exchange.lp_solver == ExchangeLpSolver::Simplex) {
    SimplexBasis start{basis.theta, {}};
    for (std::size_t c = 0; c < constraints.size(); ++c) {
      basis.points[c].resize(constraints[c].points.size(), BasisStatus::Basic);
      start.rows.insert(start.rows.end(), basis.points[c].begin(), basis.points[c].end());
    }
    lr = solve_linear_program_simplex(setup.lp, start);
    result.simplex_pivots += lr.iterations;
    basis.theta = start.variables;
    auto row = start.rows.begin();
    for (auto& statuses : basis.points)
      for (auto& status : statuses) status = *row++;
  } else {
    LinearProgramOptions lpo;
    if (round > 0) lpo.start = theta;
    lr = solve_linear_program(setup.lp, lpo);
    result.ipopt_iterations += lr.iterations;
    ++result.ipopt_calls;
    add_linear_solver_name(result.ipopt_linear_solver, lr.linear_solver);
  }
  if (lr.status == SolveStatus::Solved) {
    theta = lr.x;
    return true;
  }
  const std::string reason = fixed_violation(setup, o.feasibility_margin_N);
  result.status = lr.status == SolveStatus::Infeasible || !reason.empty() ? SolveStatus::Infeasible : SolveStatus::Failed;
  result.message = !reason.empty() ? reason
                                   : "the exchange LP of round " + std::to_string(round + 1) + " was not solved (" +
                                         (o.exchange.lp_solver == ExchangeLpSolver::Simplex ? "Clp: " : "Ipopt: ") +
                                         lr.solver_status + ")";
  return false;
}

// Keep the LPs small: initial points far from active leave the next LP. A pruned constraint that
// becomes violated is caught by the exact minimum and comes back as a sticky point.
void prune_far_points(SosSetup& setup, const Eigen::VectorXd& theta, double prune_slack_N, ExchangeBasis& basis) {
  for (std::size_t k = 0; k < setup.constraints.size(); ++k) {
    auto& c = setup.constraints[k];
    auto& statuses = basis.points[k];
    statuses.resize(c.points.size(), BasisStatus::Basic);
    const Polynomial g = c.at(theta);
    for (std::size_t i = c.points.size(); i-- > 0;)
      if (!c.sticky[i] && g(c.points[i]) > prune_slack_N) {
        c.points.erase(c.points.begin() + static_cast<std::ptrdiff_t>(i));
        c.sticky.erase(c.sticky.begin() + static_cast<std::ptrdiff_t>(i));
        statuses.erase(statuses.begin() + static_cast<std::ptrdiff_t>(i));
      }
  }
}

// Whether the exchange's end is a solution: no fixed violation, converged to the tolerance,
// bounded; otherwise result's status and message say why.
bool exchange_verdict(const SosSetup& setup, const SosSettings& o, bool converged, double tolerance_N,
                      const Eigen::VectorXd& theta, SosProgramResult& result) {
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
  if (setup.free_coefficients > 0 && (theta.cwiseAbs().maxCoeff() > 0.999 * o.exchange.coefficient_bound_N)) {
    result.status = SolveStatus::Failed;
    result.message = "the SOS program is unbounded: a free coefficient of Y reached the bound " +
                     std::to_string(o.exchange.coefficient_bound_N) + " N";
    return false;
  }
  return true;
}

}  // namespace

bool solve_by_exchange(SosSetup& setup, const SosSettings& o, Eigen::VectorXd& theta, SosProgramResult& result,
                       SequentialLpBasis* final_basis, double tolerance_N) {
  const Stopwatch solve;
  const int n_theta = setup.free_coefficients;
  if (const std::string reason = fixed_violation(setup, o.feasibility_margin_N); !reason.empty()) {
    result.status = SolveStatus::Infeasible;
    result.message = reason;
    result.solve_seconds = solve.seconds();
    return false;
  }
  theta = Eigen::VectorXd::Zero(n_theta);
  ExchangeBasis basis{std::vector<BasisStatus>(static_cast<std::size_t>(n_theta), BasisStatus::AtLower),
                      std::vector<std::vector<BasisStatus>>(setup.constraints.size())};
  if (final_basis && final_basis->step.size() == basis.theta.size() &&
      final_basis->reserve_row.size() == setup.constraints.size()) {
    // A second call goes on from the first one's basis (points it added since start inactive).
    basis.theta = final_basis->step;
    basis.points = final_basis->reserve_row;
  }
  bool converged = false;
  for (int round = 0; round < o.max_exchange_rounds; ++round) {
    result.exchange_rounds = round + 1;
    if (n_theta > 0) {
      result.lp_points = build_exchange_rows(setup, o.feasibility_margin_N);
      if (!solve_round(setup, o, round, basis, theta, result)) {
        result.solve_seconds = solve.seconds();
        return false;
      }
      prune_far_points(setup, theta, o.exchange.prune_slack_N, basis);
    }
    if (add_violated_points(setup, theta, o.feasibility_margin_N, result.min_constraint_value_N, tolerance_N)) continue;
    converged = true;
    break;
  }
  result.solve_seconds = solve.seconds();
  if (final_basis) {
    final_basis->step = basis.theta;
    final_basis->reserve_row = basis.points;
    final_basis->reserve_slack.assign(basis.points.size(), {});
  }
  return exchange_verdict(setup, o, converged, tolerance_N, theta, result);
}

}  // namespace flatsos::planner::detail
