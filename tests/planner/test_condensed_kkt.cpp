// The condensed KKT solve (inequality rows' slack and multiplier pairs eliminated first, the rest
// by the dense LDL^T) through Ipopt's ma27 calling convention, against Eigen on Ipopt-shaped
// systems: the pairs it finds, the inertia (eigenvalues), the solution (pivoted LU), singular
// pair blocks, patterns where a pair would touch another, triplets that are not the analysed
// pattern, and the slot's scatter plans (one per analysis).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Dense>

#include "flatsos/planner/numerics/ipopt_linear_solver.hpp"
#include "numerics/condensed_kkt.hpp"
#include "kkt_triplets.hpp"
#include "numerics/ipopt_dense_kkt.hpp"

namespace fd = flatsos::planner::detail;

namespace {

struct Triplets : flatsos::test::KktTriplets {
  // Adds a(i, j) (0-based) in a random triangle, sometimes split into two duplicates.
  void add(std::mt19937& rng, int i, int j, double v) {
    std::uniform_int_distribution<int> coin(0, 3);
    const bool upper = coin(rng) % 2 == 0;
    const int r = upper ? std::min(i, j) : std::max(i, j), c = upper ? std::max(i, j) : std::min(i, j);
    if (coin(rng) == 0) {
      KktTriplets::add(r, c, 0.25 * v);
      KktTriplets::add(c, r, 0.75 * v);
    } else {
      KktTriplets::add(r, c, v);
    }
  }
};

// Ipopt's augmented system in its order (x, s, c, d):
//   [W + Sigma_x, 0, J_c^T, J_d^T; 0, Sigma_s, 0, -I; J_c, 0, -delta, 0; J_d, -I, 0, -delta]
// with W dense (indefinite unless `convex`), sparse Jacobian rows, barrier diagonals spanning
// 10^-spread to 10^spread (Ipopt's reach 1e-8 .. 1e8 near an optimum). Runs of `shared`
// consecutive inequality rows use the same columns (as the rows of one time point do).
Triplets ipopt_kkt(std::mt19937& rng, int nx, int equalities, int inequalities, double delta, bool convex,
                   double spread = 8.0, int shared = 1) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> exponent(-spread, spread), unit(0.0, 1.0);
  Triplets t;
  t.n = nx + inequalities + equalities + inequalities;
  const int s0 = nx, c0 = nx + inequalities, d0 = c0 + equalities;
  Eigen::MatrixXd W(nx, nx);
  for (int j = 0; j < nx; ++j)
    for (int i = j; i < nx; ++i) W(i, j) = W(j, i) = g(rng);
  if (convex) W = (W * W.transpose()).eval();
  for (int j = 0; j < nx; ++j)
    for (int i = j; i < nx; ++i) t.add(rng, i, j, W(i, j) + (i == j ? std::pow(10.0, exponent(rng)) : 0.0));
  auto random_columns = [&] {
    std::vector<int> columns;
    for (int j = 0; j < nx; ++j)
      if (unit(rng) < 0.3) columns.push_back(j);
    return columns;
  };
  auto jacobian_row = [&](int row, const std::vector<int>& columns) {
    for (int j : columns) t.add(rng, row, j, g(rng));
  };
  std::vector<int> columns;
  for (int i = 0; i < inequalities; ++i) {
    t.add(rng, s0 + i, s0 + i, std::pow(10.0, exponent(rng)));
    t.add(rng, s0 + i, d0 + i, -1.0);
    if (delta != 0.0) t.add(rng, d0 + i, d0 + i, -delta);
    if (i % shared == 0) columns = random_columns();
    jacobian_row(d0 + i, columns);
  }
  for (int i = 0; i < equalities; ++i) {
    if (delta != 0.0) t.add(rng, c0 + i, c0 + i, -delta);
    jacobian_row(c0 + i, random_columns());
  }
  return t;
}

struct SlotResult {
  int flag = 0, rank = 0, negative = 0;
  Eigen::VectorXd x;
};

// The slot's analysis of t's pattern: what Ipopt keeps for the factorizations.
struct Analysis {
  int flag = 0, la = 0, liw = 0, nsteps = 0;
  std::vector<int> ikeep;
};

Analysis analyse(const Triplets& t) {
  int dim = t.n, nz = static_cast<int>(t.values.size());
  int icntl[30], info[20], iflag = 0;
  double cntl[5], ops = 0.0;
  fd::dense_kkt_defaults(icntl, cntl);
  Analysis an;
  std::vector<int> scratch(static_cast<std::size_t>(2 * nz + 3 * dim + 1)), iw1(static_cast<std::size_t>(2 * dim));
  an.ikeep.resize(static_cast<std::size_t>(3 * dim));
  int lscratch = static_cast<int>(scratch.size());
  fd::dense_kkt_analyse(&dim, &nz, t.irn.data(), t.icn.data(), scratch.data(), &lscratch, an.ikeep.data(), iw1.data(),
                        &an.nsteps, &iflag, icntl, cntl, info, &ops);
  an.flag = info[0];
  an.la = info[4];
  an.liw = info[5];
  return an;
}

// Factor (workspace as asked) and solve through the slot, after its analysis.
SlotResult factor_and_solve(const Triplets& t, Analysis& an, const Eigen::VectorXd& b) {
  int dim = t.n, nz = static_cast<int>(t.values.size());
  int icntl[30], info[20], maxfrt = 0, nsteps = an.nsteps;
  double cntl[5];
  fd::dense_kkt_defaults(icntl, cntl);
  std::vector<int> iw1(static_cast<std::size_t>(2 * dim));
  SlotResult r;
  int la = an.la, liw = an.liw;
  int* ikeep = an.ikeep.data();
  std::vector<double> a(static_cast<std::size_t>(la));
  std::copy(t.values.begin(), t.values.end(), a.begin());
  std::vector<int> iw(static_cast<std::size_t>(liw));
  fd::dense_kkt_factor(&dim, &nz, t.irn.data(), t.icn.data(), a.data(), &la, iw.data(), &liw, ikeep, &nsteps, &maxfrt,
                       iw1.data(), icntl, cntl, info);
  r.flag = info[0];
  r.rank = info[1];
  r.negative = info[14];
  if (info[0] != 0) return r;
  r.x = b;
  std::vector<double> w(static_cast<std::size_t>(maxfrt));
  std::vector<int> iw1_solve(static_cast<std::size_t>(nsteps));
  fd::dense_kkt_solve(&dim, a.data(), &la, iw.data(), &liw, w.data(), &maxfrt, r.x.data(), iw1_solve.data(), &nsteps, icntl,
                      cntl);
  return r;
}

// Analyse, factor and solve through the slot.
SlotResult through_slot(const Triplets& t, const Eigen::VectorXd& b) {
  Analysis an = analyse(t);
  if (an.flag != 0) {
    SlotResult r;
    r.flag = an.flag;
    return r;
  }
  return factor_and_solve(t, an, b);
}

int negative_eigenvalues(const Eigen::MatrixXd& a) {
  const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(a, Eigen::EigenvaluesOnly).eigenvalues();
  return static_cast<int>((ev.array() < 0.0).count());
}

}  // namespace

TEST(CondensedKkt, FindsEveryInequalityRowsPairAndKeepsVariablesAndEqualitiesInTheCore) {
  std::mt19937 rng(3);
  const int nx = 12, eq = 5, in = 150;
  const Triplets t = ipopt_kkt(rng, nx, eq, in, 0.0, false);
  const fd::CondensedPattern p = fd::find_eliminable_pairs(t.n, static_cast<int>(t.values.size()), t.irn.data(), t.icn.data());
  EXPECT_EQ(p.pairs, in);
  EXPECT_EQ(p.core, nx + eq);
  for (int i = 0; i < nx; ++i) EXPECT_GE(p.role[static_cast<std::size_t>(i)], 0);
  for (int i = 0; i < in; ++i) {
    const int s = p.role[static_cast<std::size_t>(nx + i)], d = p.role[static_cast<std::size_t>(nx + in + eq + i)];
    ASSERT_LT(s, 0);
    EXPECT_EQ(d, s - 1) << "the slack and the multiplier of row " << i << " form one pair";
  }
}

TEST(CondensedKkt, AgreesWithEigenOnIpoptShapedSystems) {
  std::mt19937 rng(4);
  struct Case {
    int nx, eq, in;
    double delta;
    bool convex;
    int shared = 1;
  };
  // Above kDenseKktMaxDimension, so the slot condenses: with and without equality rows and
  // regularization, convex (the inertia Ipopt wants) and not; rows with columns of their own,
  // and runs of rows sharing theirs (summed as one dense update: 2 and 3 rows pair by pair, 6
  // and 30 together, 7 as a run and a remainder).
  for (const Case& c : {Case{20, 0, 150, 0.0, true}, Case{20, 0, 150, 0.0, false}, Case{15, 6, 120, 1e-8, false},
                        Case{30, 4, 200, 0.0, true}, Case{20, 0, 150, 0.0, false, 2}, Case{15, 6, 120, 1e-8, false, 3},
                        Case{30, 4, 200, 0.0, true, 6}, Case{25, 0, 240, 0.0, false, 30},
                        Case{20, 3, 150, 1e-8, false, 7}})
    for (const double spread : {1.0, 8.0}) {
      const Triplets t = ipopt_kkt(rng, c.nx, c.eq, c.in, c.delta, c.convex, spread, c.shared);
      ASSERT_GT(t.n, flatsos::planner::kDenseKktMaxDimension);
      const Eigen::MatrixXd A = t.dense();
      const Eigen::VectorXd b = Eigen::VectorXd::Random(t.n);
      const SlotResult r = through_slot(t, b);
      ASSERT_EQ(r.flag, 0) << "n = " << t.n;
      EXPECT_EQ(r.rank, t.n);
      EXPECT_EQ(r.negative, negative_eigenvalues(A))
          << "n = " << t.n << ", spread " << spread << ", shared " << c.shared;
      // Backward stable: the residual is rounding of the matrix times the solution. (With the
      // barrier's spread the condition number reaches 1e14, where no forward comparison means
      // anything: Eigen's full-pivoting LU then leaves a residual 1e7 times larger.)
      const double backward = (A * r.x - b).norm() / (A.norm() * r.x.norm() + b.norm());
      EXPECT_LT(backward, 1e-14) << "n = " << t.n << ", spread " << spread;
      if (spread > 1.0) continue;
      // Well conditioned: the same solution.
      const Eigen::VectorXd reference = A.fullPivLu().solve(b);
      EXPECT_LE((r.x - reference).cwiseAbs().maxCoeff(), 1e-9 * reference.cwiseAbs().maxCoeff()) << "n = " << t.n;
    }
}

TEST(CondensedKkt, ASingularPairBlockIsReportedWithTheRank) {
  std::mt19937 rng(5);
  Triplets t = ipopt_kkt(rng, 10, 0, 120, 0.0, true);
  // Row 7's block [1, -1; -1, 1]: singular whatever its coupling to the variables.
  const int s = 10 + 7, d = 10 + 120 + 7;
  for (std::size_t e = 0; e < t.values.size(); ++e)
    if (t.irn[e] - 1 == s && t.icn[e] - 1 == s) t.values[e] = 0.0;
  t.add(rng, s, s, 1.0);
  t.add(rng, d, d, 1.0);
  const SlotResult r = through_slot(t, Eigen::VectorXd::Ones(t.n));
  EXPECT_EQ(r.flag, 3);
  EXPECT_EQ(r.rank, t.n - 1);
}

TEST(CondensedKkt, APairThatWouldTouchAnotherStaysInTheCore) {
  // s1 - d1 - d2 - s2 (d1 and d2 coupled, as no Ipopt system has them): the first pair is
  // eliminated, the second stays in the core, and the solve is still exact.
  std::mt19937 rng(6);
  Triplets t = ipopt_kkt(rng, 8, 0, 110, 0.0, true, 1.0);
  const int d1 = 8 + 110 + 3, d2 = 8 + 110 + 4;
  t.add(rng, d1, d2, 0.5);
  const fd::CondensedPattern p = fd::find_eliminable_pairs(t.n, static_cast<int>(t.values.size()), t.irn.data(), t.icn.data());
  EXPECT_EQ(p.pairs, 109);
  EXPECT_LT(p.role[static_cast<std::size_t>(d1)], 0);
  EXPECT_GE(p.role[static_cast<std::size_t>(d2)], 0);
  EXPECT_GE(p.role[static_cast<std::size_t>(8 + 4)], 0);  // d2's slack
  const Eigen::MatrixXd A = t.dense();
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(t.n, -1.0, 1.0);
  const SlotResult r = through_slot(t, b);
  ASSERT_EQ(r.flag, 0);
  EXPECT_EQ(r.negative, negative_eigenvalues(A));
  EXPECT_LE((r.x - A.fullPivLu().solve(b)).cwiseAbs().maxCoeff(), 1e-8 * r.x.cwiseAbs().maxCoeff());
}

TEST(CondensedKkt, TripletsThatAreNotTheAnalysedPatternAreRefused) {
  std::mt19937 rng(7);
  const int nx = 6, in = 100, d0 = nx + in;
  const Triplets t = ipopt_kkt(rng, nx, 0, in, 0.0, true, 1.0);  // well conditioned: solutions compare
  const fd::CondensedPattern p = fd::find_eliminable_pairs(t.n, static_cast<int>(t.values.size()), t.irn.data(), t.icn.data());
  std::vector<int> iw(static_cast<std::size_t>(fd::condensed_integer_workspace(p)));
  std::vector<double> real(static_cast<std::size_t>(fd::condensed_real_workspace(p)));
  fd::Inertia inertia;
  EXPECT_TRUE(fd::factor_condensed(t.n, static_cast<int>(t.values.size()), t.irn.data(), t.icn.data(), t.values.data(), p,
                                   iw.data(), real.data(), inertia));
  // A coupling of row 0's multiplier to a variable its Jacobian row does not have.
  const Eigen::MatrixXd A = t.dense();
  int missing = -1;
  for (int j = 0; j < nx && missing < 0; ++j)
    if (A(d0, j) == 0.0) missing = j;
  ASSERT_GE(missing, 0);
  Triplets more = t;
  more.irn.push_back(d0 + 1);
  more.icn.push_back(missing + 1);
  more.values.push_back(1.0);
  EXPECT_FALSE(fd::factor_condensed(more.n, static_cast<int>(more.values.size()), more.irn.data(), more.icn.data(),
                                    more.values.data(), p, iw.data(), real.data(), inertia));
  // Through the slot, with the analysis of t: as many triplets, one coupling moved to that
  // column. The slot's scatter plan is t's: the factorization must notice and build the moved
  // pattern's (its roles still hold, so it is factored, as itself), and an added coupling is
  // refused as above.
  Analysis an = analyse(t);
  ASSERT_EQ(an.flag, 0);
  int present = -1;
  for (int j = 0; j < nx && present < 0; ++j)
    if (A(d0, j) != 0.0) present = j;
  ASSERT_GE(present, 0);
  Triplets moved = t;
  std::size_t moved_entries = 0;  // every triplet of that coupling (it may be split in two)
  for (std::size_t e = 0; e < moved.values.size(); ++e) {
    const int i = moved.irn[e] - 1, j = moved.icn[e] - 1;
    if ((i == d0 && j == present) || (j == d0 && i == present)) {
      moved.irn[e] = d0 + 1;
      moved.icn[e] = missing + 1;
      ++moved_entries;
    }
  }
  ASSERT_GT(moved_entries, 0u);
  ASSERT_GT((moved.dense() - A).norm(), 0.0);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(t.n, -1.0, 1.0);
  for (const Triplets* u : {static_cast<const Triplets*>(&moved), &t}) {
    const SlotResult r = factor_and_solve(*u, an, b);
    ASSERT_EQ(r.flag, 0);
    const Eigen::VectorXd reference = u->dense().fullPivLu().solve(b);
    EXPECT_LE((r.x - reference).cwiseAbs().maxCoeff(), 1e-9 * reference.cwiseAbs().maxCoeff());
  }
  EXPECT_LT(factor_and_solve(more, an, b).flag, 0);  // a triplet more: not factored
}

TEST(CondensedKkt, EachAnalysisFactorsWithItsOwnPlanAndADroppedPlanIsBuiltAgain) {
  // The slot keeps the scatter plans of the last few analyses, keyed by a serial number in
  // ikeep: twelve patterns analysed first (the first ones' plans dropped), then factored and
  // solved newest first and again with new values, each against its own matrix.
  std::mt19937 rng(8);
  std::vector<Triplets> systems;
  std::vector<Analysis> analyses;
  for (int k = 0; k < 12; ++k) {
    systems.push_back(ipopt_kkt(rng, 10 + k, k % 3, 110 + 7 * k, 0.0, k % 2 == 0, 1.0, 1 + k % 4));
    analyses.push_back(analyse(systems.back()));
    ASSERT_EQ(analyses.back().flag, 0);
  }
  for (int pass = 0; pass < 2; ++pass)
    for (int k = 11; k >= 0; --k) {
      Triplets& t = systems[static_cast<std::size_t>(k)];
      if (pass == 1)
        for (double& v : t.values) v *= 1.5;
      const Eigen::MatrixXd A = t.dense();
      const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(t.n, -1.0, 2.0);
      const SlotResult r = factor_and_solve(t, analyses[static_cast<std::size_t>(k)], b);
      ASSERT_EQ(r.flag, 0) << "system " << k << ", pass " << pass;
      EXPECT_EQ(r.negative, negative_eigenvalues(A)) << "system " << k << ", pass " << pass;
      EXPECT_LE((r.x - A.fullPivLu().solve(b)).cwiseAbs().maxCoeff(), 1e-8 * r.x.cwiseAbs().maxCoeff())
          << "system " << k << ", pass " << pass;
    }
}
