// The per-frame program of static optimization (separable_power_program.hpp): for p = 2 against
// an independent optimum found by enumerating every active set; for other exponents by the
// optimality conditions; and what it says when the rows cannot be met inside the bounds.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Dense>

#include "flatsos/planner/separable_power_program.hpp"

namespace fpl = flatsos::planner;

namespace {

// A feasible program: rows x muscles, B of mixed signs (agonists and antagonists), b = B x0 with
// x0 inside [0, 1].
fpl::SeparablePowerProgram random_program(std::mt19937& rng, int rows, int muscles, double exponent) {
  std::uniform_real_distribution<double> arm(-0.05, 0.05), force(200.0, 1500.0), unit(0.05, 0.95), w(0.5, 2.0);
  fpl::SeparablePowerProgram P;
  P.B.resize(rows, muscles);
  for (int j = 0; j < muscles; ++j) {
    const double F = force(rng);
    for (int i = 0; i < rows; ++i) P.B(i, j) = arm(rng) * F;
  }
  Eigen::VectorXd x0(muscles);
  for (int j = 0; j < muscles; ++j) x0[j] = unit(rng) * (j % 3 == 0 ? 1.0 : 0.2);
  P.b = P.B * x0;
  P.weights.resize(muscles);
  for (int j = 0; j < muscles; ++j) P.weights[j] = w(rng);
  P.lower = Eigen::VectorXd::Zero(muscles);
  P.upper = Eigen::VectorXd::Ones(muscles);
  P.exponent = exponent;
  return P;
}

// p = 2 by brute force: every assignment of each variable to its lower bound, its upper bound or
// free; the free ones from the equality-constrained least squares (KKT system); the best
// assignment whose x is inside the bounds and meets the rows.
double enumerated_optimum(const fpl::SeparablePowerProgram& P, Eigen::VectorXd& best_x) {
  const int n = static_cast<int>(P.B.cols()), rows = static_cast<int>(P.B.rows());
  double best = INFINITY;
  int combos = 1;
  for (int j = 0; j < n; ++j) combos *= 3;
  for (int c = 0; c < combos; ++c) {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
    std::vector<int> free;
    int code = c;
    for (int j = 0; j < n; ++j, code /= 3) {
      if (code % 3 == 0) x[j] = P.lower[j];
      else if (code % 3 == 1) x[j] = P.upper[j];
      else free.push_back(j);
    }
    const Eigen::VectorXd rhs = P.b - P.B * x;
    const int f = static_cast<int>(free.size());
    // min sum_free w x^2 s.t. B_free x_free = rhs: [2W B^T; B 0] [x; -mu] = [0; rhs].
    Eigen::MatrixXd K = Eigen::MatrixXd::Zero(f + rows, f + rows);
    Eigen::VectorXd r = Eigen::VectorXd::Zero(f + rows);
    for (int k = 0; k < f; ++k) {
      K(k, k) = 2.0 * P.weights[free[static_cast<std::size_t>(k)]];
      for (int i = 0; i < rows; ++i) K(f + i, k) = K(k, f + i) = P.B(i, free[static_cast<std::size_t>(k)]);
    }
    r.tail(rows) = rhs;
    const Eigen::VectorXd sol = K.completeOrthogonalDecomposition().solve(r);
    for (int k = 0; k < f; ++k) x[free[static_cast<std::size_t>(k)]] = sol[k];
    if ((P.B * x - P.b).cwiseAbs().maxCoeff() > 1e-8 * std::max(1.0, P.b.cwiseAbs().maxCoeff())) continue;
    if ((x.array() < P.lower.array() - 1e-12).any() || (x.array() > P.upper.array() + 1e-12).any()) continue;
    const double value = (P.weights.array() * x.array().square()).sum();
    if (value < best) best = value, best_x = x;
  }
  return best;
}

}  // namespace

TEST(SeparablePowerProgram, SquaresReachTheOptimumOfEveryActiveSet) {
  std::mt19937 rng(7);
  int with_bounds_active = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const fpl::SeparablePowerProgram P = random_program(rng, trial % 2 ? 2 : 3, 7, 2.0);
    const fpl::SeparablePowerSolution s = fpl::solve_separable_power_program(P);
    ASSERT_TRUE(s.solved) << s.message;
    Eigen::VectorXd reference;
    const double best = enumerated_optimum(P, reference);
    ASSERT_TRUE(std::isfinite(best));
    EXPECT_NEAR(s.objective, best, 1e-9 * std::max(1.0, best)) << "trial " << trial;
    EXPECT_LT((s.x - reference).cwiseAbs().maxCoeff(), 1e-7) << "trial " << trial;
    EXPECT_LT(s.residual, 1e-9 * std::max(1.0, P.b.cwiseAbs().maxCoeff()));
    with_bounds_active += ((s.x.array() <= 1e-12) || (s.x.array() >= 1.0 - 1e-12)).any() ? 1 : 0;
  }
  EXPECT_GE(with_bounds_active, 10) << "the test needs programs whose bounds are active";
}

TEST(SeparablePowerProgram, OtherExponentsMeetTheOptimalityConditions) {
  // x_j minimizes w_j |x|^p - s_j x over its bounds, with s = B^T lambda: inside the bounds the
  // derivative p w |x|^(p-1) sign(x) equals s_j; at the lower bound it is >= s_j, at the upper <=.
  std::mt19937 rng(11);
  for (double p : {1.5, 3.0, 4.0}) {
    for (int trial = 0; trial < 10; ++trial) {
      const fpl::SeparablePowerProgram P = random_program(rng, 2, 6, p);
      const fpl::SeparablePowerSolution s = fpl::solve_separable_power_program(P);
      ASSERT_TRUE(s.solved) << "p = " << p << ": " << s.message;
      const Eigen::VectorXd sj = P.B.transpose() * s.multipliers;
      for (Eigen::Index j = 0; j < sj.size(); ++j) {
        const double x = s.x[j], d = p * P.weights[j] * std::pow(std::abs(x), p - 1.0) * (x < 0 ? -1.0 : 1.0);
        const double tol = 1e-6 * (1.0 + std::abs(sj[j]));
        if (x <= P.lower[j] + 1e-12) EXPECT_GE(d, sj[j] - tol) << "p " << p << " muscle " << j;
        else if (x >= P.upper[j] - 1e-12) EXPECT_LE(d, sj[j] + tol) << "p " << p << " muscle " << j;
        else EXPECT_NEAR(d, sj[j], tol) << "p " << p << " muscle " << j;
      }
      EXPECT_LT(s.residual, 1e-9 * std::max(1.0, P.b.cwiseAbs().maxCoeff()));
    }
  }
}

TEST(SeparablePowerProgram, UnboundedVariablesAreReservesThatAlwaysMeetTheRows) {
  // A reserve actuator per row (unbounded control, one N m per unit): a row no muscle can meet is
  // met by its reserve, and only there.
  std::mt19937 rng(3);
  fpl::SeparablePowerProgram P = random_program(rng, 2, 5, 2.0);
  P.b[0] *= 1e4;  // far beyond what the muscles can do
  EXPECT_FALSE(fpl::solve_separable_power_program(P).solved);
  const Eigen::Index m = P.B.cols();
  P.B.conservativeResize(2, m + 2);
  P.B.rightCols(2) = Eigen::Matrix2d::Identity();
  P.weights.conservativeResize(m + 2);
  P.weights.tail(2).setConstant(1.0);
  P.lower.conservativeResize(m + 2);
  P.upper.conservativeResize(m + 2);
  P.lower.tail(2).setConstant(-INFINITY);
  P.upper.tail(2).setConstant(INFINITY);
  const fpl::SeparablePowerSolution s = fpl::solve_separable_power_program(P);
  ASSERT_TRUE(s.solved) << s.message;
  EXPECT_GT(std::abs(s.x[m]), 1.0);
}

TEST(SeparablePowerProgram, SaysWhichRowCannotBeMetAndRefusesBadPrograms) {
  std::mt19937 rng(5);
  fpl::SeparablePowerProgram P = random_program(rng, 2, 5, 2.0);
  P.b[1] = 1e6;
  const fpl::SeparablePowerSolution s = fpl::solve_separable_power_program(P);
  EXPECT_FALSE(s.solved);
  EXPECT_TRUE(s.infeasible);
  EXPECT_EQ(s.worst_row, 1);
  EXPECT_NE(s.message.find("no solution within the bounds: row 1"), std::string::npos) << s.message;
  // Out of iterations is said as such, not as infeasibility.
  const fpl::SeparablePowerSolution early = fpl::solve_separable_power_program(random_program(rng, 2, 5, 3.0), 1e-14, 1);
  if (!early.solved) {
    EXPECT_FALSE(early.infeasible);
    EXPECT_NE(early.message.find("stopped before it converged"), std::string::npos) << early.message;
  }
  fpl::SeparablePowerProgram bad = random_program(rng, 2, 5, 2.0);
  bad.exponent = 1.0;
  EXPECT_THROW(fpl::solve_separable_power_program(bad), std::invalid_argument);
  bad = random_program(rng, 2, 5, 2.0);
  bad.weights[2] = 0.0;
  EXPECT_THROW(fpl::solve_separable_power_program(bad), std::invalid_argument);
  bad = random_program(rng, 2, 5, 2.0);
  bad.lower[1] = 2.0;
  EXPECT_THROW(fpl::solve_separable_power_program(bad), std::invalid_argument);
  bad = random_program(rng, 2, 5, 2.0);
  bad.B.resize(0, 5);
  bad.b.resize(0);
  EXPECT_THROW(fpl::solve_separable_power_program(bad), std::invalid_argument);
  bad = random_program(rng, 2, 5, 2.0);
  bad.b.resize(3);
  EXPECT_THROW(fpl::solve_separable_power_program(bad), std::invalid_argument);
}
