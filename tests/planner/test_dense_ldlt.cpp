// flatsos's dense Bunch-Kaufman LDL^T against Eigen (inertia from eigenvalues, solutions from a
// pivoted LU) on random symmetric indefinite matrices and KKT-shaped ones (zero blocks that need
// 2x2 pivots), on singular and near-singular matrices, and through Ipopt's ma27 calling
// convention (1-based triplets of either triangle with duplicates, workspace negotiation).
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include <Eigen/Dense>

#include "numerics/dense_ldlt.hpp"
#include "numerics/ipopt_dense_kkt.hpp"

namespace fd = flatsos::planner::detail;

namespace {

Eigen::MatrixXd random_symmetric(std::mt19937& rng, int n) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd a(n, n);
  for (int j = 0; j < n; ++j)
    for (int i = j; i < n; ++i) a(i, j) = a(j, i) = g(rng);
  return a;
}

// Ipopt's KKT shape: [H + Sigma, J^T; J, -delta I] with delta often 0 (a zero block: 1x1
// pivots alone would fail there).
Eigen::MatrixXd random_kkt(std::mt19937& rng, int n, int m, double delta) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> sigma(-8.0, 8.0);  // log10 of the barrier diagonal
  Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(n + m, n + m);
  for (int i = 0; i < n; ++i) kkt(i, i) = std::pow(10.0, sigma(rng));
  for (int i = 0; i < m; ++i) {
    for (int j = 0; j < n; ++j) kkt(n + i, j) = kkt(j, n + i) = g(rng);
    kkt(n + i, n + i) = -delta;
  }
  return kkt;
}

struct EigenInertia {
  int positive = 0, negative = 0, zero = 0;
};

EigenInertia eigen_inertia(const Eigen::MatrixXd& a, double zero_below) {
  const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(a, Eigen::EigenvaluesOnly).eigenvalues();
  EigenInertia in;
  for (double v : ev) {
    if (v > zero_below) ++in.positive;
    else if (v < -zero_below) ++in.negative;
    else ++in.zero;
  }
  return in;
}

void expect_same_inertia_and_solution(const Eigen::MatrixXd& a, std::mt19937& rng, const char* what) {
  const int n = static_cast<int>(a.rows());
  const fd::DenseLdlt ldlt(a);
  const EigenInertia expected = eigen_inertia(a, 0.0);
  EXPECT_EQ(ldlt.inertia().positive, expected.positive) << what << ", n = " << n;
  EXPECT_EQ(ldlt.inertia().negative, expected.negative) << what << ", n = " << n;
  EXPECT_EQ(ldlt.inertia().zero, 0) << what << ", n = " << n;
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::VectorXd b(n);
  for (auto& v : b) v = g(rng);
  const Eigen::VectorXd x = ldlt.solve(b);
  const Eigen::VectorXd reference = a.fullPivLu().solve(b);
  // Backward stable: the residual at rounding level of |A| |x|; the solutions agree within the
  // condition number's reach.
  const double scale = a.cwiseAbs().maxCoeff() * x.cwiseAbs().maxCoeff() * n;
  EXPECT_LE((a * x - b).cwiseAbs().maxCoeff(), 1e-13 * scale) << what << ", n = " << n;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a);
  const double condition = svd.singularValues()(0) / svd.singularValues()(n - 1);
  EXPECT_LE((x - reference).norm(), 1e-14 * condition * reference.norm() * n) << what << ", n = " << n;
}

}  // namespace

TEST(DenseLdlt, RandomSymmetricIndefiniteMatricesMatchEigen) {
  std::mt19937 rng(11);
  for (int n : {1, 2, 3, 5, 8, 13, 40, 97})
    for (int trial = 0; trial < 5; ++trial) expect_same_inertia_and_solution(random_symmetric(rng, n), rng, "random");
}

TEST(DenseLdlt, KktMatricesWithZeroBlocksMatchEigen) {
  std::mt19937 rng(12);
  for (const auto& [n, m] : std::vector<std::pair<int, int>>{{1, 1}, {4, 2}, {4, 22}, {10, 10}, {30, 12}, {60, 90}})
    for (double delta : {0.0, 1e-8})
      for (int trial = 0; trial < 3; ++trial) {
        if (m > n && delta == 0.0) continue;  // J^T has more columns than rank: singular
        expect_same_inertia_and_solution(random_kkt(rng, n, m, delta), rng, "KKT");
      }
}

TEST(DenseLdlt, ZeroDiagonalNeedsTwoByTwoPivots) {
  // Every diagonal entry is 0: a 1x1 pivot rule alone would divide by zero.
  Eigen::Matrix3d a;
  a << 0, 2, 1,  //
      2, 0, 3,   //
      1, 3, 0;
  const fd::DenseLdlt ldlt(a);
  const EigenInertia expected = eigen_inertia(a, 0.0);
  EXPECT_EQ(ldlt.inertia().positive, expected.positive);
  EXPECT_EQ(ldlt.inertia().negative, expected.negative);
  const Eigen::Vector3d b(1.0, -2.0, 0.5);
  EXPECT_LE((a * ldlt.solve(b) - b).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(DenseLdlt, ExactlySingularMatricesReportTheirRank) {
  // A zero row and column, and a rank-one block whose elimination cancels exactly.
  Eigen::MatrixXd a(4, 4);
  a << 2, 2, 0, 1,  //
      2, 2, 0, 1,   //
      0, 0, 0, 0,   //
      1, 1, 0, -3;
  const fd::DenseLdlt ldlt(a);
  const EigenInertia expected = eigen_inertia(a, 1e-12);
  EXPECT_EQ(ldlt.inertia().zero, 2);
  EXPECT_EQ(ldlt.rank(), 2);
  EXPECT_EQ(ldlt.inertia().positive, expected.positive);
  EXPECT_EQ(ldlt.inertia().negative, expected.negative);
  // A consistent right-hand side is still solved (the zero pivots' components set to 0).
  const Eigen::Vector4d x_true(1.0, 0.0, 0.0, 2.0);
  const Eigen::Vector4d b = a * x_true;
  const Eigen::VectorXd x = ldlt.solve(b);
  EXPECT_TRUE(x.allFinite());
  EXPECT_LE((a * x - b).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(DenseLdlt, NumericallySingularMatricesStayFiniteAndKeepTheRestOfTheInertia) {
  // Rank n - 1 by construction, but rounding leaves the last pivot at ~1e-16: it may count as
  // positive or negative (as MUMPS and MA27 at their zero-pivot threshold 0 would), every
  // eigenvalue clearly away from 0 must be counted with its sign.
  std::mt19937 rng(13);
  for (int n : {3, 10, 40}) {
    const Eigen::MatrixXd q = Eigen::HouseholderQR<Eigen::MatrixXd>(random_symmetric(rng, n)).householderQ();
    Eigen::VectorXd lambda(n);
    for (int i = 0; i < n; ++i) lambda(i) = (i % 2 ? -1.0 : 1.0) * (1.0 + i);
    lambda(n / 2) = 0.0;
    const Eigen::MatrixXd a = q * lambda.asDiagonal() * q.transpose();
    const fd::DenseLdlt ldlt(a);
    const EigenInertia clear = eigen_inertia(a, 1e-8);
    EXPECT_EQ(clear.zero, 1);
    EXPECT_GE(ldlt.inertia().positive, clear.positive) << n;
    EXPECT_GE(ldlt.inertia().negative, clear.negative) << n;
    EXPECT_LE(ldlt.inertia().positive, clear.positive + 1) << n;
    EXPECT_LE(ldlt.inertia().negative, clear.negative + 1) << n;
  }
}

TEST(DenseLdlt, NearSingularMatricesKeepInertiaAndBackwardStability) {
  // Eigenvalues down to 1e-10 of the largest: still counted right, residuals at rounding level.
  std::mt19937 rng(14);
  for (int n : {6, 30}) {
    const Eigen::MatrixXd q = Eigen::HouseholderQR<Eigen::MatrixXd>(random_symmetric(rng, n)).householderQ();
    Eigen::VectorXd lambda(n);
    for (int i = 0; i < n; ++i) lambda(i) = (i % 3 ? -1.0 : 1.0) * std::pow(10.0, -10.0 * i / (n - 1));
    const Eigen::MatrixXd a = q * lambda.asDiagonal() * q.transpose();
    const fd::DenseLdlt ldlt(a);
    EXPECT_EQ(ldlt.inertia().positive, (lambda.array() > 0).count()) << n;
    EXPECT_EQ(ldlt.inertia().negative, (lambda.array() < 0).count()) << n;
    const Eigen::VectorXd b = Eigen::VectorXd::Ones(n);
    const Eigen::VectorXd x = ldlt.solve(b);
    EXPECT_LE((a * x - b).cwiseAbs().maxCoeff(), 1e-13 * x.cwiseAbs().maxCoeff() * n) << n;
  }
}

TEST(DenseLdlt, IpoptCallingConventionTripletsDuplicatesAndWorkspace) {
  std::mt19937 rng(15);
  const Eigen::MatrixXd a = random_kkt(rng, 5, 3, 0.0);
  const int n = 8;
  // 1-based triplets, each off-diagonal entry once in a random triangle, some split into two
  // duplicates that must be summed.
  std::vector<int> irn, icn;
  std::vector<double> values;
  std::uniform_int_distribution<int> coin(0, 2);
  for (int j = 0; j < n; ++j)
    for (int i = j; i < n; ++i) {
      if (a(i, j) == 0.0 && i != j) continue;
      const bool upper = coin(rng) == 0;
      const int r = upper ? j + 1 : i + 1, c = upper ? i + 1 : j + 1;
      if (coin(rng) == 1) {
        irn.insert(irn.end(), {r, c});
        icn.insert(icn.end(), {c, r});
        values.insert(values.end(), {0.25 * a(i, j), 0.75 * a(i, j)});
      } else {
        irn.push_back(r);
        icn.push_back(c);
        values.push_back(a(i, j));
      }
    }
  int dim = n, nz = static_cast<int>(values.size());
  int icntl[30];
  double cntl[5];
  fd::dense_kkt_defaults(icntl, cntl);
  int info[20];
  int nsteps = 0, iflag = 0;
  double ops = 0.0;
  std::vector<int> scratch(static_cast<std::size_t>(4 * nz + 6 * n + 2)), ikeep(3 * n), iw1(2 * n);
  int lscratch = static_cast<int>(scratch.size());
  fd::dense_kkt_analyse(&dim, &nz, irn.data(), icn.data(), scratch.data(), &lscratch, ikeep.data(), iw1.data(), &nsteps,
                        &iflag, icntl, cntl, info, &ops);
  ASSERT_EQ(info[0], 0);
  EXPECT_GE(nsteps, 1);
  const int la_needed = info[4], liw_needed = info[5];

  // Too little workspace: the flags and sizes Ipopt reacts to, nothing written.
  std::vector<double> small(static_cast<std::size_t>(la_needed - 1));
  std::copy(values.begin(), values.end(), small.begin());
  int la = la_needed - 1, liw = liw_needed, maxfrt = 0;
  std::vector<int> iw(static_cast<std::size_t>(liw_needed));
  fd::dense_kkt_factor(&dim, &nz, irn.data(), icn.data(), small.data(), &la, iw.data(), &liw, ikeep.data(), &nsteps,
                       &maxfrt, iw1.data(), icntl, cntl, info);
  EXPECT_EQ(info[0], -4);
  EXPECT_EQ(info[1], la_needed);
  la = la_needed;
  liw = liw_needed - 1;
  std::vector<double> work(static_cast<std::size_t>(la_needed));
  std::copy(values.begin(), values.end(), work.begin());
  fd::dense_kkt_factor(&dim, &nz, irn.data(), icn.data(), work.data(), &la, iw.data(), &liw, ikeep.data(), &nsteps,
                       &maxfrt, iw1.data(), icntl, cntl, info);
  EXPECT_EQ(info[0], -3);
  EXPECT_EQ(info[1], liw_needed);

  liw = liw_needed;
  fd::dense_kkt_factor(&dim, &nz, irn.data(), icn.data(), work.data(), &la, iw.data(), &liw, ikeep.data(), &nsteps,
                       &maxfrt, iw1.data(), icntl, cntl, info);
  ASSERT_EQ(info[0], 0);
  EXPECT_EQ(info[1], n);  // the rank
  EXPECT_EQ(info[14], eigen_inertia(a, 0.0).negative);
  EXPECT_GE(maxfrt, 1);
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
  Eigen::VectorXd x = b;
  std::vector<double> w(static_cast<std::size_t>(maxfrt));
  std::vector<int> iw1_solve(static_cast<std::size_t>(nsteps));
  fd::dense_kkt_solve(&dim, work.data(), &la, iw.data(), &liw, w.data(), &maxfrt, x.data(), iw1_solve.data(), &nsteps,
                      icntl, cntl);
  // The same solution as the factorization called directly (the slot adds no arithmetic), and
  // a backward-stable one.
  EXPECT_EQ(x, fd::DenseLdlt(a).solve(b));
  EXPECT_LE((a * x - b).cwiseAbs().maxCoeff(), 1e-13 * a.cwiseAbs().maxCoeff() * x.cwiseAbs().maxCoeff() * n);

  // An index out of range is refused at the analysis, naming the entry.
  irn[2] = n + 1;
  fd::dense_kkt_analyse(&dim, &nz, irn.data(), icn.data(), scratch.data(), &lscratch, ikeep.data(), iw1.data(), &nsteps,
                        &iflag, icntl, cntl, info, &ops);
  EXPECT_EQ(info[0], 1);
  EXPECT_EQ(info[1], 3);
}

TEST(DenseLdlt, SingularMatrixThroughTheSlotReportsRankDeficiency) {
  // Two equal constraint rows and no regularization: Ipopt must hear "singular" (flag 3 with
  // the rank) to perturb the constraint block.
  int dim = 3, nz = 4;
  const int irn[] = {1, 3, 2, 3}, icn[] = {1, 1, 1, 2};
  std::vector<double> a = {1.0, 1.0, 1.0, 0.0};  // [[1, 1, 1], [1, 0, 0], [1, 0, 0]]
  int icntl[30], info[20], nsteps = 0, iflag = 0, maxfrt = 0;
  double cntl[5], ops = 0.0;
  fd::dense_kkt_defaults(icntl, cntl);
  std::vector<int> scratch(64), ikeep(9), iw1(6);
  int lscratch = 64;
  fd::dense_kkt_analyse(&dim, &nz, irn, icn, scratch.data(), &lscratch, ikeep.data(), iw1.data(), &nsteps, &iflag,
                        icntl, cntl, info, &ops);
  ASSERT_EQ(info[0], 0);
  int la = info[4], liw = info[5];
  a.resize(static_cast<std::size_t>(la));
  std::vector<int> iw(static_cast<std::size_t>(liw));
  fd::dense_kkt_factor(&dim, &nz, irn, icn, a.data(), &la, iw.data(), &liw, ikeep.data(), &nsteps, &maxfrt, iw1.data(),
                       icntl, cntl, info);
  EXPECT_EQ(info[0], 3);
  EXPECT_EQ(info[1], 2);
  EXPECT_EQ(info[14], 1);  // eigenvalues of the regular part: 1 +- sqrt(... ): one negative
}
