// The dense dual active-set QP (numerics/dense_qp.hpp) checked by the optimality conditions of a
// convex QP, which certify the optimum independently of how it was found: A x >= b, multipliers
// >= 0 and zero off the active rows, H x + g = A^T lambda. Random problems with more rows than
// unknowns, degenerate ones (repeated rows, more active rows than unknowns), infeasible ones.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "numerics/dense_qp.hpp"

namespace fd = flatsos::planner::detail;

namespace {

struct Qp {
  Eigen::MatrixXd H, A;
  Eigen::VectorXd g, b;
};

Qp random_qp(std::mt19937& rng, int n, int m, double condition) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Qp qp;
  const Eigen::MatrixXd Q = Eigen::MatrixXd::NullaryExpr(n, n, [&] { return normal(rng); }).householderQr().householderQ();
  Eigen::VectorXd eig(n);
  for (int i = 0; i < n; ++i) eig[i] = std::pow(condition, -static_cast<double>(i) / std::max(n - 1, 1));
  qp.H = Q * eig.asDiagonal() * Q.transpose();
  qp.H = 0.5 * (qp.H + qp.H.transpose()).eval();
  qp.g = Eigen::VectorXd::NullaryExpr(n, [&] { return 3.0 * normal(rng); });
  qp.A = Eigen::MatrixXd::NullaryExpr(m, n, [&] { return normal(rng); });
  // Feasible by construction: every row holds at a random point x0 with slack >= 0.
  const Eigen::VectorXd x0 = Eigen::VectorXd::NullaryExpr(n, [&] { return normal(rng); });
  qp.b = qp.A * x0 - Eigen::VectorXd::NullaryExpr(m, [&] { return std::abs(normal(rng)); });
  return qp;
}

// The largest violation of the optimality conditions, relative to the data's size.
double kkt_residual(const Qp& qp, const Eigen::VectorXd& x, const Eigen::VectorXd& lambda) {
  const Eigen::VectorXd stationarity = qp.H * x + qp.g - qp.A.transpose() * lambda;
  double worst = stationarity.cwiseAbs().maxCoeff() / (1.0 + qp.g.cwiseAbs().maxCoeff());
  if (qp.b.size() == 0) return worst;
  const Eigen::VectorXd slack = qp.A * x - qp.b;
  worst = std::max(worst, -slack.minCoeff());
  worst = std::max(worst, -lambda.minCoeff());
  return std::max(worst, (lambda.array() * slack.array()).abs().maxCoeff());
}

}  // namespace

TEST(DenseQp, RandomProblemsMeetTheOptimalityConditions) {
  std::mt19937 rng(7);
  fd::DenseQpWorkspace w;  // reused across sizes, as the sequential QP does
  int with_active_rows = 0, with_drops = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 1 + trial % 12, m = (trial % 5) * n * 3;
    const Qp qp = random_qp(rng, n, m, trial % 3 == 0 ? 1e6 : 10.0);
    Eigen::VectorXd x, lambda;
    const fd::DenseQpResult r = fd::solve_dense_qp(qp.H, qp.g, qp.A, qp.b, w, x, &lambda);
    ASSERT_TRUE(r.solved) << "trial " << trial << ": " << r.failure;
    EXPECT_LT(kkt_residual(qp, x, lambda), 1e-8) << "trial " << trial << " n " << n << " m " << m;
    EXPECT_NEAR(r.objective, 0.5 * x.dot(qp.H * x) + qp.g.dot(x), 1e-12 * (1.0 + std::abs(r.objective)));
    const auto active = lambda.size() > 0 ? (lambda.array() > 0.0).count() : 0;
    if (active > 0) ++with_active_rows;
    if (r.iterations > active) ++with_drops;  // a row joined and left again
  }
  // The test exercises the active set, rows dropped included, not only x = -H^-1 g.
  EXPECT_GT(with_active_rows, 150);
  EXPECT_GT(with_drops, 20);
}

// Many rows of which few bind, as the effort's QPs have (13 000 rows, some hundred active): after
// the first pass over every row, later passes compute only the rows that can have become
// violated since (|A_i| |x - x_then| against their slack then), and the optimum is the same.
TEST(DenseQp, ManyRowsFewBindingPassesComputeOnlyTheRowsThatCanBeViolated) {
  std::mt19937 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  fd::DenseQpWorkspace w;
  int partial = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 10 + trial, m = 100 * n;
    Qp qp = random_qp(rng, n, m, trial % 2 ? 1e4 : 10.0);
    // Most rows far from binding: their slack at the feasible point grows tenfold.
    for (int i = 0; i < m; ++i)
      if (i % 20 != 0) qp.b[i] -= 10.0 * std::abs(normal(rng));
    Eigen::VectorXd x, lambda;
    const fd::DenseQpResult r = fd::solve_dense_qp(qp.H, qp.g, qp.A, qp.b, w, x, &lambda);
    ASSERT_TRUE(r.solved) << "trial " << trial << ": " << r.failure;
    EXPECT_LT(kkt_residual(qp, x, lambda), 1e-8) << "trial " << trial;
    EXPECT_GE(w.full_passes, 1);
    partial += w.partial_passes;
  }
  EXPECT_GT(partial, 20);  // the partial passes are exercised, not only full ones
}

TEST(DenseQp, RepeatedRowsAndMoreActiveRowsThanUnknowns) {
  // minimize |x - (2, 2)|^2 with x1 <= 1 three times over, x2 <= 1, x1 + x2 <= 2: the optimum
  // (1, 1) has five active rows in two unknowns.
  Eigen::MatrixXd H = 2.0 * Eigen::MatrixXd::Identity(2, 2);
  Eigen::VectorXd g(2);
  g << -4.0, -4.0;
  Eigen::MatrixXd A(5, 2);
  A << -1, 0, -1, 0, -1, 0, 0, -1, -1, -1;
  Eigen::VectorXd b(5);
  b << -1, -1, -1, -1, -2;
  fd::DenseQpWorkspace w;
  Eigen::VectorXd x, lambda;
  const fd::DenseQpResult r = fd::solve_dense_qp(H, g, A, b, w, x, &lambda);
  ASSERT_TRUE(r.solved) << r.failure;
  EXPECT_NEAR(x[0], 1.0, 1e-12);
  EXPECT_NEAR(x[1], 1.0, 1e-12);
  const Qp qp{H, A, g, b};
  EXPECT_LT(kkt_residual(qp, x, lambda), 1e-12);
}

TEST(DenseQp, AnInfeasibleProblemIsReportedNotSolved) {
  Eigen::MatrixXd H = Eigen::MatrixXd::Identity(2, 2);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(2);
  Eigen::MatrixXd A(2, 2);
  A << 1, 1, -1, -1;  // x1 + x2 >= 1 and x1 + x2 <= -1
  Eigen::VectorXd b(2);
  b << 1, 1;
  fd::DenseQpWorkspace w;
  Eigen::VectorXd x;
  const fd::DenseQpResult r = fd::solve_dense_qp(H, g, A, b, w, x);
  EXPECT_FALSE(r.solved);
  EXPECT_NE(r.failure.find("infeasible"), std::string::npos) << r.failure;
}

TEST(DenseQp, BadInputThrowsNamingTheProblem) {
  fd::DenseQpWorkspace w;
  Eigen::VectorXd x;
  Eigen::MatrixXd H(2, 2);
  H << 1, 0, 0, -1;
  try {
    fd::solve_dense_qp(H, Eigen::VectorXd::Zero(2), Eigen::MatrixXd::Zero(0, 2), Eigen::VectorXd::Zero(0), w, x);
    FAIL() << "an indefinite H was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("positive definite"), std::string::npos) << e.what();
  }
  EXPECT_THROW(fd::solve_dense_qp(Eigen::MatrixXd::Identity(2, 2), Eigen::VectorXd::Zero(3), Eigen::MatrixXd::Zero(0, 2),
                                  Eigen::VectorXd::Zero(0), w, x),
               std::invalid_argument);
  // A non-finite entry of A, also in a row a hint offers first (A is checked through A x).
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(3, 2);
  for (const double bad : {std::nan(""), HUGE_VAL}) {
    A(2, 1) = bad;
    for (const std::vector<int>& hint : {std::vector<int>{}, std::vector<int>{2}}) {
      try {
        fd::solve_dense_qp(Eigen::MatrixXd::Identity(2, 2), Eigen::VectorXd::Ones(2), A, Eigen::VectorXd::Zero(3), w, x,
                           nullptr, 1e-10, &hint);
        ADD_FAILURE() << "A with " << bad << " was accepted";
      } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("NaN or Inf"), std::string::npos) << e.what();
      }
    }
  }
}

// A hint (rows to try first) changes the work, not the optimum: the last active set of a nearby
// problem, a hint with rows that hold, repeated and out-of-range entries, all reach the same
// optimality conditions, and the last active set spares most iterations' scans.
TEST(DenseQp, AHintOfRowsToTryFirstReachesTheSameOptimum) {
  std::mt19937 rng(11);
  std::normal_distribution<double> normal(0.0, 1.0);
  fd::DenseQpWorkspace w;
  int started = 0;  // hot solves that factored the hinted rows at once
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 4 + trial % 9, m = 6 * n;
    Qp qp = random_qp(rng, n, m, trial % 2 ? 1e4 : 10.0);
    Eigen::VectorXd x0, lambda0;
    ASSERT_TRUE(fd::solve_dense_qp(qp.H, qp.g, qp.A, qp.b, w, x0, &lambda0).solved);
    std::vector<int> hint = w.active;
    hint.push_back(-3), hint.push_back(m + 5), hint.push_back(0), hint.push_back(0);
    // A nearby problem, as the next step of a sequential QP sees.
    qp.g += 0.05 * Eigen::VectorXd::NullaryExpr(n, [&] { return normal(rng); });
    Eigen::VectorXd x_cold, lambda_cold, x_hot, lambda_hot;
    const fd::DenseQpResult cold = fd::solve_dense_qp(qp.H, qp.g, qp.A, qp.b, w, x_cold, &lambda_cold);
    const fd::DenseQpResult hot = fd::solve_dense_qp(qp.H, qp.g, qp.A, qp.b, w, x_hot, &lambda_hot, 1e-10, &hint);
    ASSERT_TRUE(cold.solved && hot.solved) << hot.failure;
    if (!hint.empty() && w.started_rows > 0) ++started;
    EXPECT_LT(kkt_residual(qp, x_hot, lambda_hot), 1e-8) << "trial " << trial;
    EXPECT_LT((x_hot - x_cold).cwiseAbs().maxCoeff(), 1e-7 * (1.0 + x_cold.cwiseAbs().maxCoeff())) << "trial " << trial;
    EXPECT_NEAR(hot.objective, cold.objective, 1e-9 * (1.0 + std::abs(cold.objective)));
  }
  std::printf("hinted solves started on the hinted rows: %d of 40\n", started);
  EXPECT_GE(started, 30);  // of 40: the last optimum's rows, the same but for g
}

// Hints that are not an optimum's active set: rows whose multipliers would be negative (they
// leave before the start is factored), rows that repeat another's constraint (dependent: tried one
// by one instead) and more rows than unknowns. Each reaches the optimum of the cold solve.
TEST(DenseQp, HintedRowsThatDoNotBindOrAreDependentStillReachTheOptimum) {
  std::mt19937 rng(5);
  fd::DenseQpWorkspace w;
  int started = 0, one_by_one = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const int n = 3 + trial % 8, m = 5 * n;
    Qp qp = random_qp(rng, n, m, trial % 2 ? 1e3 : 10.0);
    std::vector<int> hint;
    if (trial % 3 == 0) {
      for (int r = 0; r < n / 2; ++r) hint.push_back(r);  // arbitrary rows: some would pull
    } else if (trial % 3 == 1) {
      qp.A.row(1) = 2.0 * qp.A.row(0);  // row 1 is row 0's constraint, scaled
      qp.b[1] = 2.0 * qp.b[0];
      hint = {0, 1, 2};
    } else {
      for (int r = 0; r <= n; ++r) hint.push_back(r);  // more rows than unknowns: the first n taken
    }
    Eigen::VectorXd x_cold, lambda_cold, x_hot, lambda_hot;
    const fd::DenseQpResult cold = fd::solve_dense_qp(qp.H, qp.g, qp.A, qp.b, w, x_cold, &lambda_cold);
    const fd::DenseQpResult hot = fd::solve_dense_qp(qp.H, qp.g, qp.A, qp.b, w, x_hot, &lambda_hot, 1e-10, &hint);
    ASSERT_TRUE(cold.solved && hot.solved) << hot.failure;
    (w.started_rows > 0 ? started : one_by_one) += 1;
    if (trial % 3 == 1) {
      EXPECT_EQ(w.started_rows, 0) << "dependent rows factored, trial " << trial;
    }
    EXPECT_LT(kkt_residual(qp, x_hot, lambda_hot), 1e-8) << "trial " << trial;
    EXPECT_LT((x_hot - x_cold).cwiseAbs().maxCoeff(), 1e-7 * (1.0 + x_cold.cwiseAbs().maxCoeff())) << "trial " << trial;
  }
  std::printf("started on the hinted rows %d, one by one %d\n", started, one_by_one);
  EXPECT_GT(started, 0);
  EXPECT_GE(one_by_one, 20);  // at least the 20 with dependent rows
}

// A's rows stored sparse: the same optimum and multipliers as stored dense (their sums rounded
// otherwise, so not necessarily the same passes), on rows with a few nonzeros each (as the
// effort's bound rows), with and without a hint.
TEST(DenseQp, SparseRowsGiveWhatDenseRowsGive) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  fd::DenseQpWorkspace w;
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 5 + trial % 20, m = 12 * n;
    Qp qp = random_qp(rng, n, m, trial % 2 ? 1e4 : 10.0);
    for (int i = 0; i < m; ++i)  // about a fifth of each row, some rows all zero
      for (int j = 0; j < n; ++j)
        if (unit(rng) > 0.2) qp.A(i, j) = 0.0;
    const fd::SparseRows sparse = qp.A.sparseView();
    Eigen::VectorXd x_dense, lambda_dense, x_sparse, lambda_sparse;
    const fd::DenseQpResult dense = fd::solve_dense_qp(qp.H, qp.g, qp.A, qp.b, w, x_dense, &lambda_dense);
    std::vector<int> hint = w.active;
    const fd::DenseQpResult r = fd::solve_dense_qp(qp.H, qp.g, sparse, qp.b, w, x_sparse, &lambda_sparse);
    ASSERT_EQ(dense.solved, r.solved) << "trial " << trial;
    if (!r.solved) continue;
    EXPECT_LT(kkt_residual(qp, x_sparse, lambda_sparse), 1e-8) << "trial " << trial;
    EXPECT_LT((x_sparse - x_dense).cwiseAbs().maxCoeff(), 1e-9 * (1.0 + x_dense.cwiseAbs().maxCoeff())) << "trial " << trial;
    EXPECT_LT((lambda_sparse - lambda_dense).cwiseAbs().maxCoeff(), 1e-7 * (1.0 + lambda_dense.cwiseAbs().maxCoeff()));
    const fd::DenseQpResult hot = fd::solve_dense_qp(qp.H, qp.g, sparse, qp.b, w, x_sparse, &lambda_sparse, 1e-10, &hint);
    ASSERT_TRUE(hot.solved) << hot.failure;
    EXPECT_LT(kkt_residual(qp, x_sparse, lambda_sparse), 1e-8) << "trial " << trial;
  }
}
