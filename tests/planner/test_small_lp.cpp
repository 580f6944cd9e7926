// The exact small-LP solver agrees with Ipopt on random LPs of the exchange's shape, reports
// infeasible rows as infeasible, and handles degenerate vertices.
#include <gtest/gtest.h>

#include <random>

#include "flatsos/planner/numerics/small_lp.hpp"

namespace fpl = flatsos::planner;

namespace {
fpl::LinearProgram random_lp(std::mt19937& rng, int n, int rows) {
  std::normal_distribution<double> g(0.0, 1.0);
  fpl::LinearProgram lp;
  lp.cost.resize(n);
  for (auto& c : lp.cost) c = g(rng);
  lp.G.resize(rows, n);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < n; ++j) lp.G(i, j) = g(rng);
  // Feasible by construction: x0 satisfies every row with slack.
  Eigen::VectorXd x0(n);
  for (auto& v : x0) v = g(rng);
  lp.row_lower = lp.G * x0 - Eigen::VectorXd::Constant(rows, 0.5).cwiseAbs();
  for (int i = 0; i < rows; ++i) lp.row_lower[i] -= std::abs(g(rng));
  lp.row_upper = Eigen::VectorXd::Constant(rows, 1e19);
  lp.x_lower = Eigen::VectorXd::Constant(n, -100.0);
  lp.x_upper = Eigen::VectorXd::Constant(n, 100.0);
  return lp;
}
}  // namespace

TEST(SmallLp, AgreesWithIpoptOnRandomLps) {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 1 + trial % 6, rows = 5 + 7 * (trial % 9);
    const auto lp = random_lp(rng, n, rows);
    const auto exact = fpl::solve_small_lp(lp);
    const auto ipopt = fpl::solve_linear_program(lp);
    ASSERT_EQ(exact.status, fpl::SolveStatus::Solved) << "trial " << trial;
    ASSERT_EQ(ipopt.status, fpl::SolveStatus::Solved) << "trial " << trial;
    EXPECT_NEAR(exact.objective, ipopt.objective, 1e-6 * (1 + std::abs(ipopt.objective))) << "trial " << trial;
    EXPECT_GE((lp.G * exact.x - lp.row_lower).minCoeff(), -1e-9);
    EXPECT_LE((exact.x - lp.x_upper).maxCoeff(), 1e-9);
    EXPECT_GE((exact.x - lp.x_lower).minCoeff(), -1e-9);
  }
}

TEST(SmallLp, InfeasibleRowsAreReportedAsInfeasible) {
  fpl::LinearProgram lp;
  lp.cost = Eigen::Vector2d(1.0, 1.0);
  lp.G = (Eigen::MatrixXd(2, 2) << 1, 0, -1, 0).finished();  // x0 >= 2 and -x0 >= -1
  lp.row_lower = Eigen::Vector2d(2.0, -1.0);
  lp.row_upper = Eigen::Vector2d::Constant(1e19);
  lp.x_lower = Eigen::Vector2d::Constant(-10.0);
  lp.x_upper = Eigen::Vector2d::Constant(10.0);
  EXPECT_EQ(fpl::solve_small_lp(lp).status, fpl::SolveStatus::Infeasible);
}

TEST(SmallLp, DegenerateVertexAndBoxOptimum) {
  // Three rows through the optimum (1, 1) of min x + y: degenerate in 2-D.
  fpl::LinearProgram lp;
  lp.cost = Eigen::Vector2d(1.0, 1.0);
  lp.G = (Eigen::MatrixXd(3, 2) << 1, 0, 0, 1, 1, 1).finished();
  lp.row_lower = Eigen::Vector3d(1.0, 1.0, 2.0);
  lp.row_upper = Eigen::Vector3d::Constant(1e19);
  lp.x_lower = Eigen::Vector2d::Constant(-10.0);
  lp.x_upper = Eigen::Vector2d::Constant(10.0);
  const auto r = fpl::solve_small_lp(lp);
  ASSERT_EQ(r.status, fpl::SolveStatus::Solved);
  EXPECT_NEAR(r.x[0], 1.0, 1e-12);
  EXPECT_NEAR(r.x[1], 1.0, 1e-12);
  // Unconstrained direction: the box bound is the optimum.
  lp.cost = Eigen::Vector2d(1.0, -1.0);
  const auto box = fpl::solve_small_lp(lp);
  ASSERT_EQ(box.status, fpl::SolveStatus::Solved);
  EXPECT_NEAR(box.x[1], 10.0, 1e-12);
  EXPECT_THROW(fpl::solve_small_lp([&] { auto bad = lp; bad.x_upper[0] = 1e19; return bad; }()), std::invalid_argument);
}
