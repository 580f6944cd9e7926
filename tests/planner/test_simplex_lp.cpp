// The Clp wrapper: agrees with Ipopt on random LPs of the exchange's shape (few variables, many
// rows), maps infeasible and unbounded problems to their statuses, reaches degenerate vertices
// exactly, honours both row bounds and "no bound" (1e19), and rejects bad data by name.
#include <gtest/gtest.h>

#include <string>

#include <random>

#include "flatsos/planner/numerics/simplex_lp.hpp"

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
  lp.row_lower = lp.G * x0 - Eigen::VectorXd::Constant(rows, 0.5);
  for (int i = 0; i < rows; ++i) lp.row_lower[i] -= std::abs(g(rng));
  lp.row_upper = Eigen::VectorXd::Constant(rows, 1e19);
  lp.x_lower = Eigen::VectorXd::Constant(n, -100.0);
  lp.x_upper = Eigen::VectorXd::Constant(n, 100.0);
  return lp;
}

fpl::LinearProgram two_variables(const Eigen::MatrixXd& G, const Eigen::VectorXd& lower) {
  fpl::LinearProgram lp;
  lp.cost = Eigen::Vector2d(1.0, 1.0);
  lp.G = G;
  lp.row_lower = lower;
  lp.row_upper = Eigen::VectorXd::Constant(G.rows(), 1e19);
  lp.x_lower = Eigen::Vector2d::Constant(-10.0);
  lp.x_upper = Eigen::Vector2d::Constant(10.0);
  return lp;
}
}  // namespace

TEST(SimplexLp, AgreesWithIpoptOnRandomLps) {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 1 + trial % 12 * 4, rows = 5 + 37 * (trial % 9);
    const auto lp = random_lp(rng, n, rows);
    const auto simplex = fpl::solve_linear_program_simplex(lp);
    const auto ipopt = fpl::solve_linear_program(lp);
    ASSERT_EQ(simplex.status, fpl::SolveStatus::Solved) << "trial " << trial << ": " << simplex.solver_status;
    ASSERT_EQ(ipopt.status, fpl::SolveStatus::Solved) << "trial " << trial;
    EXPECT_NEAR(simplex.objective, ipopt.objective, 1e-6 * (1 + std::abs(ipopt.objective))) << "trial " << trial;
    EXPECT_GE((lp.G * simplex.x - lp.row_lower).minCoeff(), -1e-9);
    EXPECT_LE((simplex.x - lp.x_upper).maxCoeff(), 1e-9);
    EXPECT_GE((simplex.x - lp.x_lower).minCoeff(), -1e-9);
  }
}

TEST(SimplexLp, InfeasibleAndUnboundedAreReportedAsSuch) {
  // x0 >= 2 and -x0 >= -1.
  auto lp = two_variables((Eigen::MatrixXd(2, 2) << 1, 0, -1, 0).finished(), Eigen::Vector2d(2.0, -1.0));
  const auto infeasible = fpl::solve_linear_program_simplex(lp);
  EXPECT_EQ(infeasible.status, fpl::SolveStatus::Infeasible) << infeasible.solver_status;
  // min x0 + x1 with x1 free below and no row holding it: unbounded.
  lp = two_variables((Eigen::MatrixXd(1, 2) << 1, 0).finished(), Eigen::VectorXd::Constant(1, 1.0));
  lp.x_lower[1] = -1e19;
  const auto unbounded = fpl::solve_linear_program_simplex(lp);
  EXPECT_EQ(unbounded.status, fpl::SolveStatus::Failed);
  EXPECT_NE(unbounded.solver_status.find("unbounded"), std::string::npos) << unbounded.solver_status;
}

TEST(SimplexLp, DegenerateVertexBoxOptimumAndRowUpperBounds) {
  // Three rows through the optimum (1, 1) of min x + y: degenerate in 2-D.
  auto lp = two_variables((Eigen::MatrixXd(3, 2) << 1, 0, 0, 1, 1, 1).finished(), Eigen::Vector3d(1.0, 1.0, 2.0));
  const auto r = fpl::solve_linear_program_simplex(lp);
  ASSERT_EQ(r.status, fpl::SolveStatus::Solved);
  EXPECT_NEAR(r.x[0], 1.0, 1e-12);
  EXPECT_NEAR(r.x[1], 1.0, 1e-12);
  EXPECT_NEAR(r.objective, 2.0, 1e-12);
  // Unconstrained direction: the box bound is the optimum.
  lp.cost = Eigen::Vector2d(1.0, -1.0);
  const auto box = fpl::solve_linear_program_simplex(lp);
  ASSERT_EQ(box.status, fpl::SolveStatus::Solved);
  EXPECT_NEAR(box.x[1], 10.0, 1e-12);
  // An upper row bound x0 + x1 <= 5 binds the same direction.
  lp.row_upper[2] = 5.0;
  const auto capped = fpl::solve_linear_program_simplex(lp);
  ASSERT_EQ(capped.status, fpl::SolveStatus::Solved);
  EXPECT_NEAR(capped.x[0] + capped.x[1], 5.0, 1e-12);
  EXPECT_NEAR(capped.x[0], 1.0, 1e-12);
}

TEST(SimplexLp, BadDataIsRejected) {
  auto lp = two_variables((Eigen::MatrixXd(1, 2) << 1, 0).finished(), Eigen::VectorXd::Constant(1, 1.0));
  auto bad = lp;
  bad.G(0, 1) = std::nan("");
  EXPECT_THROW(fpl::solve_linear_program_simplex(bad), std::invalid_argument);
  bad = lp;
  bad.row_lower.resize(2);
  EXPECT_THROW(fpl::solve_linear_program_simplex(bad), std::invalid_argument);
  // Clp aborts the process on a cost of 1e25 (an assertion): refused before, naming the scale.
  bad = lp;
  bad.cost[0] = 1e25;
  try {
    fpl::solve_linear_program_simplex(bad);
    ADD_FAILURE() << "accepted a cost of 1e25";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("out of range"), std::string::npos) << e.what();
  }
}

TEST(SimplexLp, SparseAndDenseFormsGiveTheSameOptimum) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 10; ++trial) {
    auto lp = random_lp(rng, 3 + trial, 20 + 10 * trial);
    // Thin the rows out: the sparse form must keep exactly the nonzeros.
    for (Eigen::Index i = 0; i < lp.G.rows(); ++i)
      for (Eigen::Index j = 0; j < lp.G.cols(); ++j)
        if ((i + j) % 3 == 0) lp.G(i, j) = 0.0;
    lp.row_lower = -1.0 - lp.row_lower.cwiseAbs().array();  // x = 0 stays feasible after the thinning
    fpl::SparseLinearProgram sparse{lp.cost, lp.G.sparseView(), lp.row_lower, lp.row_upper, lp.x_lower, lp.x_upper};
    const auto a = fpl::solve_linear_program_simplex(lp);
    const auto b = fpl::solve_linear_program_simplex(sparse);
    ASSERT_EQ(a.status, fpl::SolveStatus::Solved);
    ASSERT_EQ(b.status, fpl::SolveStatus::Solved);
    EXPECT_NEAR(a.objective, b.objective, 1e-9 * (1 + std::abs(a.objective))) << trial;
  }
}

namespace {
// An LP like a sequential LP's step: random rows, a box around 0, and the same rows moved a
// little (bounds, coefficients, box) from one LP to the next.
fpl::LinearProgram perturbed(const fpl::LinearProgram& lp, std::mt19937& rng, double size) {
  std::normal_distribution<double> g(0.0, size);
  fpl::LinearProgram next = lp;
  for (Eigen::Index i = 0; i < next.G.rows(); ++i) {
    next.row_lower[i] += g(rng);
    for (Eigen::Index j = 0; j < next.G.cols(); ++j) next.G(i, j) *= 1.0 + g(rng);
  }
  const double box = 1.0 + std::abs(g(rng));
  next.x_lower.setConstant(-box);
  next.x_upper.setConstant(box);
  return next;
}
}  // namespace

TEST(SimplexLp, AWarmStartReachesTheColdOptimumInFewerPivots) {
  std::mt19937 rng(7);
  auto lp = random_lp(rng, 30, 400);
  lp.x_lower.setConstant(-1.0);
  lp.x_upper.setConstant(1.0);
  lp.row_lower = lp.row_lower.cwiseMin(-0.1);  // x = 0 inside, many rows active at the optimum
  fpl::SimplexBasis basis;
  int warm_pivots = 0, cold_pivots = 0;
  for (int step = 0; step < 8; ++step) {
    lp = perturbed(lp, rng, 1e-3);
    const auto warm = fpl::solve_linear_program_simplex(lp, basis);
    const auto cold = fpl::solve_linear_program_simplex(lp);
    ASSERT_EQ(warm.status, fpl::SolveStatus::Solved) << step;
    ASSERT_EQ(cold.status, fpl::SolveStatus::Solved) << step;
    EXPECT_NEAR(warm.objective, cold.objective, 1e-9 * (1 + std::abs(cold.objective))) << step;
    EXPECT_GE((lp.G * warm.x - lp.row_lower).minCoeff(), -1e-9) << step;
    ASSERT_EQ(basis.variables.size(), 30u);
    ASSERT_EQ(basis.rows.size(), 400u);
    if (step > 0) {  // the first solve starts cold either way
      warm_pivots += warm.iterations;
      cold_pivots += cold.iterations;
    }
  }
  EXPECT_LT(warm_pivots, cold_pivots / 3) << "warm " << warm_pivots << " vs cold " << cold_pivots;
}

TEST(SimplexLp, AStartBasisWithTheWrongCountOrSizeStillGivesTheOptimum) {
  std::mt19937 rng(3);
  const auto lp = random_lp(rng, 12, 150);
  const auto cold = fpl::solve_linear_program_simplex(lp);
  ASSERT_EQ(cold.status, fpl::SolveStatus::Solved);
  using S = fpl::BasisStatus;
  const std::vector<fpl::SimplexBasis> starts = {
      {std::vector<S>(12, S::Basic), std::vector<S>(150, S::Basic)},       // 162 basic entries for 150 rows
      {std::vector<S>(12, S::AtUpper), std::vector<S>(150, S::AtLower)},   // none basic
      {std::vector<S>(5, S::Basic), std::vector<S>(7, S::AtLower)},        // another LP's basis: ignored
  };
  for (std::size_t k = 0; k < starts.size(); ++k) {
    fpl::SimplexBasis basis = starts[k];
    const auto r = fpl::solve_linear_program_simplex(lp, basis);
    ASSERT_EQ(r.status, fpl::SolveStatus::Solved) << k;
    EXPECT_NEAR(r.objective, cold.objective, 1e-9 * (1 + std::abs(cold.objective))) << k;
    EXPECT_EQ(basis.rows.size(), 150u) << k;
  }
}

TEST(SimplexLp, StepLpsOfMixedScalesAreFeasibleUnscaled) {
  // The shape of the bounds' step LPs: a small box on the step, rows over nine decades of size,
  // elastic slacks priced at 1e4-1e8 on the rows violated at the start. Clp's tolerances act on
  // the scaled problem; five of these 200 LPs come back optimal there with slacks down to -5e-4
  // unscaled. Every result must be feasible unscaled: slacks >= 0, the box, and rows to 1e-6 of
  // their size (Clp's unscaled resolution is about 5e-7; the bounds' rows carry a margin of 1e-6
  // for it, bound_rows.hpp). Optimality is not compared: these LPs are too ill-conditioned for
  // different simplex paths to agree.
  std::mt19937 rng(1);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int n = 40, rows = 600, slacks = 60;
  for (int trial = 0; trial < 200; ++trial) {
    fpl::SparseLinearProgram lp;
    lp.cost.resize(n + slacks);
    lp.x_lower.resize(n + slacks);
    lp.x_upper.resize(n + slacks);
    const double box = std::pow(10.0, -4.0 + 4.0 * u(rng));
    for (int j = 0; j < n; ++j) {
      lp.x_lower[j] = -box;
      lp.x_upper[j] = box;
      lp.cost[j] = std::pow(10.0, -2.0 + 2.0 * u(rng)) * g(rng);
    }
    for (int j = n; j < n + slacks; ++j) {
      lp.x_lower[j] = 0.0;
      lp.x_upper[j] = 1e19;
      lp.cost[j] = 1e4 * std::pow(10.0, 4.0 * u(rng));
    }
    std::vector<Eigen::Triplet<double>> entries;
    lp.row_lower.resize(rows);
    for (int i = 0; i < rows; ++i) {
      const double size = std::pow(10.0, -6.0 + 9.0 * u(rng));
      for (int j = 0; j < n; ++j)
        if (u(rng) < 0.3) entries.emplace_back(i, j, size * g(rng));
      // The first rows are violated at 0 and have a slack; the others hold at 0.
      lp.row_lower[i] = (i < slacks ? 3.0 : -3.0) * size * box * u(rng);
      if (i < slacks) entries.emplace_back(i, n + i, 1.0);
    }
    lp.G.resize(rows, n + slacks);
    lp.G.setFromTriplets(entries.begin(), entries.end());
    lp.row_upper = Eigen::VectorXd::Constant(rows, 1e19);
    const auto r = fpl::solve_linear_program_simplex(lp);
    ASSERT_EQ(r.status, fpl::SolveStatus::Solved) << trial << ": " << r.solver_status;
    const Eigen::VectorXd activity = lp.G * r.x;
    double worst_row = 0.0;
    for (int i = 0; i < rows; ++i) {
      const double size = Eigen::RowVectorXd(lp.G.row(i)).cwiseAbs().maxCoeff();
      worst_row = std::min(worst_row, (activity[i] - lp.row_lower[i]) / size);
    }
    EXPECT_GE(worst_row, -1e-6) << trial;
    EXPECT_GE((r.x.head(n) - lp.x_lower.head(n)).minCoeff(), -1e-9 * box) << trial;
    EXPECT_LE((r.x.head(n) - lp.x_upper.head(n)).maxCoeff(), 1e-9 * box) << trial;
    EXPECT_GE(r.x.tail(slacks).minCoeff(), -1e-9) << trial;
  }
}
