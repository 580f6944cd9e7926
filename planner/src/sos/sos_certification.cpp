#include <algorithm>

#include "flatsos/planner/numerics/sos_certificate.hpp"
#include "flatsos/planner/numerics/ipopt_linear_solver.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "sos/sos_exchange.hpp"

namespace flatsos::planner::detail {

void certify_near_active_pieces(const SosSetup& setup, const Eigen::VectorXd& theta, const SosSettings& o,
                                SosProgramResult& result) {
  const Stopwatch certify;
  std::vector<Polynomial> near_active;
  for (const auto& c : setup.constraints) {
    const Polynomial g = c.at(theta);
    if (minimum_on_interval(g, 0.0, 1.0).value < o.near_active_N) {
      Eigen::VectorXd shifted = g.coefficients();
      shifted[0] += kConstraintTolerance_N;  // certified: constraint >= -1e-9 N
      near_active.emplace_back(shifted);
    }
  }
  result.near_active_pieces = static_cast<int>(near_active.size());
  if (near_active.empty()) {
    result.certified = true;
  } else {
    const CertificationResult cert = certify_nonnegative_on_unit_interval(near_active, 1e-9);
    result.certified_pieces = static_cast<int>(std::count(cert.certified.begin(), cert.certified.end(), true));
    result.certified = cert.all_certified;
    result.ipopt_iterations += cert.ipopt_iterations;
    result.ipopt_calls += cert.ipopt_calls;
    add_linear_solver_name(result.ipopt_linear_solver, cert.ipopt_linear_solver);
  }
  result.certify_seconds = certify.seconds();
}

}  // namespace flatsos::planner::detail
