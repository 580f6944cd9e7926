#pragma once
// A random feasible LP with dense rows (the exchange's and the SLP's shape): n coefficients with
// a box of +-100, `rows` lower-bounded rows that a random point meets with a slack of 0.5. Shared
// by the linear-solver tests and their benchmark.
#include <random>

#include "flatsos/planner/numerics/linear_program.hpp"

namespace flatsos::test {

inline planner::LinearProgram random_feasible_lp(std::mt19937& rng, int n, int rows) {
  std::normal_distribution<double> g(0.0, 1.0);
  planner::LinearProgram lp;
  lp.cost = Eigen::VectorXd::NullaryExpr(n, [&] { return g(rng); });
  lp.G = Eigen::MatrixXd::NullaryExpr(rows, n, [&] { return g(rng); });
  const Eigen::VectorXd x0 = Eigen::VectorXd::NullaryExpr(n, [&] { return g(rng); });
  lp.row_lower = lp.G * x0 - Eigen::VectorXd::Constant(rows, 0.5);
  lp.row_upper = Eigen::VectorXd::Constant(rows, 1e19);
  lp.x_lower = Eigen::VectorXd::Constant(n, -100.0);
  lp.x_upper = Eigen::VectorXd::Constant(n, 100.0);
  return lp;
}

}  // namespace flatsos::test
