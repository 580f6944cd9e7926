// The sparse LDL^T in time order (numerics/sparse_kkt.hpp) through Ipopt's ma27 calling
// convention, against Eigen's dense eigenvalues and pivoted LU on collocation-shaped KKT systems
// (each time point's unknowns, its rows coupling them to the previous point's): the inertia, the
// solution, the order it factors in (no fill beyond the band), duplicate triplets, refactoring
// new values, singular systems reported as singular, and triplets that are not the analysed
// pattern.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <vector>

#include "flatsos/planner/numerics/ipopt_linear_solver.hpp"
#include "kkt_triplets.hpp"
#include "numerics/ipopt_dense_kkt.hpp"
#include "numerics/sparse_kkt.hpp"

namespace fd = flatsos::planner::detail;

namespace {

struct Kkt : flatsos::test::KktTriplets {
  int primal = 0;
};

// Ipopt's augmented system [W + Sigma, J^T; J, -delta] in its order (primal first) for `points`
// time points of `per_point` unknowns and `rows` rows each; a row of point k touches point k's
// unknowns and point k - 1's. W couples neighbouring points and is indefinite.
Kkt collocation_kkt(std::mt19937& rng, int points, int per_point, int rows, double delta) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> exponent(-4.0, 4.0);
  Kkt k;
  k.primal = points * per_point;
  k.n = k.primal + points * rows;
  for (int p = 0; p < points; ++p)
    for (int a = 0; a < per_point; ++a) {
      const int i = p * per_point + a;
      k.add(i, i, g(rng) + std::pow(10.0, exponent(rng)));
      for (int b = 0; b < a; ++b) k.add(i, p * per_point + b, 0.5 * g(rng));
      if (p > 0) k.add(i, (p - 1) * per_point + a, 0.5 * g(rng));
    }
  for (int p = 0; p < points; ++p)
    for (int r = 0; r < rows; ++r) {
      const int row = k.primal + p * rows + r;
      k.add(row, row, -delta);
      for (int a = 0; a < per_point; ++a) {
        k.add(p * per_point + a, row, g(rng));  // the upper triangle: J^T
        if (p > 0 && a % 2 == 0) k.add(row, (p - 1) * per_point + a, g(rng));
      }
    }
  return k;
}

struct SlotRun {
  int flag = 0, negative = 0;
  std::vector<double> solution;
};

// Analyse, factor and solve through the slot's functions with the sparse order requested.
SlotRun through_slot(Kkt& k, const std::vector<double>& rhs) {
  const int previous = fd::set_sparse_kkt_primal_rows(k.primal);
  int n = k.n, nz = static_cast<int>(k.values.size());
  std::vector<int> iw(static_cast<std::size_t>(2 * nz + 3 * n + 1)),
      ikeep(static_cast<std::size_t>(3 * n)), iw1(2 * n);
  int liw = static_cast<int>(iw.size()), nsteps = 0, iflag = 0, maxfrt = 0;
  int icntl[30];
  double cntl[5], ops = 0.0;
  int info[20];
  fd::dense_kkt_defaults(icntl, cntl);
  fd::dense_kkt_analyse(&n, &nz, k.irn.data(), k.icn.data(), iw.data(), &liw, ikeep.data(),
                        iw1.data(), &nsteps, &iflag, icntl, cntl, info, &ops);
  fd::set_sparse_kkt_primal_rows(previous);
  EXPECT_EQ(info[0], 0);
  std::vector<double> a(static_cast<std::size_t>(std::max(info[4], nz)));
  std::copy(k.values.begin(), k.values.end(), a.begin());
  int la = static_cast<int>(a.size());
  fd::dense_kkt_factor(&n, &nz, k.irn.data(), k.icn.data(), a.data(), &la, iw.data(), &liw,
                       ikeep.data(), &nsteps, &maxfrt, iw1.data(), icntl, cntl, info);
  SlotRun out{info[0], info[14], rhs};
  if (info[0] != 0) return out;
  std::vector<double> w(static_cast<std::size_t>(std::max(maxfrt, 1)));
  fd::dense_kkt_solve(&n, a.data(), &la, iw.data(), &liw, w.data(), &maxfrt, out.solution.data(),
                      iw1.data(), &nsteps, icntl, cntl);
  return out;
}

}  // namespace

TEST(SparseKkt, InertiaAndSolutionAgreeWithDenseAlgebraAndItFactorsInTheBand) {
  std::mt19937 rng(7);
  for (double delta : {0.0, 1e-8}) {
    Kkt k = collocation_kkt(rng, 60, 5, 3, delta);  // 480 rows: above the dense solver's 200
    ASSERT_GT(k.n, flatsos::planner::kDenseKktMaxDimension);
    std::vector<double> rhs(static_cast<std::size_t>(k.n));
    std::normal_distribution<double> g(0.0, 1.0);
    for (double& r : rhs) r = g(rng);
    const SlotRun run = through_slot(k, rhs);
    ASSERT_EQ(run.flag, 0);
    const Eigen::MatrixXd A = k.dense();
    const Eigen::VectorXd eigenvalues =
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A).eigenvalues();
    EXPECT_EQ(run.negative, (eigenvalues.array() < 0.0).count());
    const Eigen::VectorXd b = Eigen::Map<const Eigen::VectorXd>(rhs.data(), k.n);
    const Eigen::VectorXd expected = A.partialPivLu().solve(b);
    const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(run.solution.data(), k.n);
    EXPECT_LE((x - expected).norm(), 1e-8 * expected.norm());
    // The order keeps the factor within the band: no more than a dense band of two points' rows.
    const auto kkt = fd::analyse_sparse_kkt(k.n, static_cast<int>(k.values.size()), k.irn.data(),
                                            k.icn.data(), k.primal);
    int negative = 0;
    ASSERT_TRUE(fd::factor_sparse_kkt(*kkt, k.values.data(), negative));
    const int band = 2 * (5 + 3);
    EXPECT_LE(kkt->factor.matrixL().nestedExpression().nonZeros(),
              static_cast<Eigen::Index>(k.n) * band);
  }
}

TEST(SparseKkt, NewValuesOnTheSamePatternAreFactoredAgain) {
  std::mt19937 rng(3);
  Kkt k = collocation_kkt(rng, 40, 4, 2, 0.0);
  const auto kkt = fd::analyse_sparse_kkt(k.n, static_cast<int>(k.values.size()), k.irn.data(),
                                          k.icn.data(), k.primal);
  EXPECT_TRUE(
      fd::same_sparse_pattern(*kkt, static_cast<int>(k.values.size()), k.irn.data(), k.icn.data()));
  for (int round = 0; round < 3; ++round) {
    for (double& v : k.values) v *= 1.0 + 0.1 * round;
    int negative = 0;
    ASSERT_TRUE(fd::factor_sparse_kkt(*kkt, k.values.data(), negative));
    Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(k.n, -1.0, 1.0);
    const Eigen::VectorXd b = x;
    fd::solve_sparse_kkt(*kkt, x.data());
    EXPECT_LE((k.dense() * x - b).norm(), 1e-9 * b.norm()) << "round " << round;
  }
  std::vector<int> other = k.irn;
  std::swap(other.front(), other.back());
  EXPECT_FALSE(
      fd::same_sparse_pattern(*kkt, static_cast<int>(k.values.size()), other.data(), k.icn.data()));
}

TEST(SparseKkt, ASingularSystemIsReportedSingular) {
  // Two rows of the same point with the same coefficients and no delta: J is rank deficient, so
  // the KKT matrix is singular; the slot says so (flag 3), and Ipopt would regularize.
  std::mt19937 rng(5);
  Kkt k = collocation_kkt(rng, 50, 4, 2, 0.0);
  const int first = k.primal + 10 * 2, second = first + 1;
  std::vector<int> irn, icn;
  std::vector<double> values;
  Kkt copy;
  copy.n = k.n;
  copy.primal = k.primal;
  for (std::size_t e = 0; e < k.values.size(); ++e) {
    const int i = k.irn[e] - 1, j = k.icn[e] - 1;
    if (i == second || j == second) continue;  // row `second` is rebuilt as a copy of `first`
    copy.add(i, j, k.values[e]);
    if (i == first && j != first) copy.add(second, j, k.values[e]);
    if (j == first && i != first) copy.add(i, second, k.values[e]);
  }
  copy.add(second, second, 0.0);
  const SlotRun run =
      through_slot(copy, std::vector<double>(static_cast<std::size_t>(copy.n), 1.0));
  EXPECT_EQ(run.flag, 3);
}
