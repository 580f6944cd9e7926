// The bounds' sequential LP on a problem of its shape, independent of muscles: a linear cost
// over many smooth concave rows ">= 0" and linear reserve rows. Its step LPs over a working set
// of rows must take the steps the LPs over every candidate row take, in far smaller LPs, and
// end at a point that satisfies the KKT conditions.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "bounds/sequential_lp.hpp"
#include "concave_rows_problem.hpp"

namespace fpd = flatsos::planner::detail;
using flatsos::testing::ConcaveRows;
using flatsos::testing::Problem;

TEST(SequentialLp, AWorkingSetTakesTheFullStepLpsStepsInSmallerLps) {
  const Problem problem;
  const Problem::Solved full = problem.solve(false), working = problem.solve(true);
  // Without the closest rows the set starts from the violated and active rows alone: rows join
  // (LPs solved again) and the steps are still the same.
  const Problem::Solved joined = problem.solve(true, 0);
  ASSERT_TRUE(joined.outcome.converged) << joined.outcome.failure;
  EXPECT_GT(joined.outcome.lp_solves, full.outcome.lp_solves);
  EXPECT_EQ(joined.outcome.iterations, full.outcome.iterations);
  EXPECT_LT((joined.x - full.x).cwiseAbs().maxCoeff(), 1e-9);
  ASSERT_TRUE(full.outcome.converged) << full.outcome.failure;
  ASSERT_TRUE(working.outcome.converged) << working.outcome.failure;
  EXPECT_EQ(working.outcome.iterations, full.outcome.iterations);
  EXPECT_LT((working.x - full.x).cwiseAbs().maxCoeff(), 1e-9);
  // The working set's LPs, solved again where rows join, hold a fraction of the rows.
  EXPECT_LT(working.outcome.lp_rows, full.outcome.lp_rows / 2)
      << working.outcome.lp_rows << " rows in " << working.outcome.lp_solves << " LPs against " << full.outcome.lp_rows;
  std::cout << "[ measure  ] " << full.outcome.iterations << " LP steps: " << full.outcome.lp_rows << " rows in "
            << full.outcome.lp_solves << " LPs, with a working set " << working.outcome.lp_rows << " rows in "
            << working.outcome.lp_solves << " LPs\n";
}

TEST(SequentialLp, EndsAtAKktPointOfEveryRow) {
  const Problem problem;
  const Problem::Solved s = problem.solve(true);
  ASSERT_TRUE(s.outcome.converged) << s.outcome.failure;
  ASSERT_FALSE(s.outcome.rows_violated);
  // Primal: every row, not only the working set's, holds to the margins the SLP imposes.
  const fpd::BoundRowsAt at = problem.rows(s.x, true);
  EXPECT_GE(*std::min_element(at.value.begin(), at.value.end()), -fpd::kBoundMargin);
  EXPECT_GE((problem.lp.G * s.x - problem.lp.row_lower).minCoeff(), -1e-6);
  EXPECT_GE(s.x.minCoeff(), 0.0);
  // Dual: cost = J' lambda + G' mu + (multipliers of x >= 0), lambda, mu >= 0, complementary.
  ASSERT_EQ(s.outcome.row_multipliers.size(), at.value.size());
  Eigen::VectorXd residual = problem.lp.cost - problem.lp.G.transpose() * s.outcome.linear_row_multipliers;
  for (const auto& t : at.jacobian) residual[t.col()] -= s.outcome.row_multipliers[static_cast<std::size_t>(t.row())] * t.value();
  int active = 0;
  for (std::size_t i = 0; i < at.value.size(); ++i) {
    EXPECT_GE(s.outcome.row_multipliers[i], 0.0);
    if (s.outcome.row_multipliers[i] > 0.0) {
      ++active;
      EXPECT_LT(std::abs(at.value[i]), 1e-6) << "row " << i << " has a multiplier but is not active";
    }
  }
  EXPECT_GT(active, 0);
  for (Eigen::Index j = 0; j < s.x.size(); ++j) {
    if (s.x[j] > 1e-9) EXPECT_NEAR(residual[j], 0.0, 1e-6) << "coefficient " << j;
    else EXPECT_GE(residual[j], -1e-6) << "coefficient " << j;  // x_j at its bound 0
  }
}

// Two rows that no x meets together (x0 >= 5 and x0 <= 1, both bent a little) among the
// concave ones: the SLP must end at a stationary point of the violation and say the rows are
// violated. Steering the penalty by the violation's own LP gets there in fewer LP steps than
// raising it only after settling at each price (41 against 94 when written), at the same point.
TEST(SequentialLp, AnInfeasibleProblemEndsAtAStationaryPointOfTheViolationSoonerWhenSteered) {
  const Problem problem;
  auto rows = [&](const Eigen::VectorXd& x, bool jacobian) {
    fpd::BoundRowsAt out = problem.rows(x, jacobian);
    const int first = static_cast<int>(out.value.size());
    const double bend = 0.01 * x.squaredNorm();
    for (const double sign : {1.0, -1.0}) {
      const double v = sign > 0 ? x[0] - 5.0 - bend : 1.0 - x[0] - bend;
      const int row = first + (sign > 0 ? 0 : 1);
      out.value.push_back(v);
      out.violation += std::max(0.0, -v);
      if (jacobian)
        for (Eigen::Index j = 0; j < x.size(); ++j)
          out.jacobian.emplace_back(row, static_cast<int>(j), (j == 0 ? sign : 0.0) - 0.02 * x[j]);
    }
    return out;
  };
  const fpd::SequentialLpLinearPart linear{problem.lp, {static_cast<std::size_t>(Problem::kReserveRows)}, 1e-6};
  auto solve = [&](bool steering, Eigen::VectorXd& x) {
    x = Eigen::VectorXd::Zero(Problem::kVariables);
    double radius = 0.1;
    flatsos::planner::SequentialLpBasis basis;
    fpd::SequentialLpSettings settings;
    settings.steering = steering;
    return fpd::solve_by_sequential_lp(linear, rows, x, radius, basis, settings);
  };
  Eigen::VectorXd x, x_unsteered;
  const fpd::SequentialLpOutcome outcome = solve(true, x), unsteered = solve(false, x_unsteered);
  ASSERT_TRUE(outcome.converged) << outcome.failure;
  EXPECT_TRUE(outcome.rows_violated);
  ASSERT_TRUE(unsteered.converged) << unsteered.failure;
  EXPECT_TRUE(unsteered.rows_violated);
  std::printf("LP steps to the violation's stationary point: %d steered, %d unsteered\n", outcome.iterations,
              unsteered.iterations);
  EXPECT_LT(outcome.iterations, unsteered.iterations);
  // Stationary for the violation (bound rows and reserve rows): no small move lowers it.
  auto violation = [&](const Eigen::VectorXd& at) {
    return rows(at, false).violation + fpd::reserve_violation_N(problem.lp, at);
  };
  const double at_end = violation(x);
  EXPECT_GE(at_end, 4.0);  // x0 - 5 and 1 - x0 cannot both be above -2
  EXPECT_NEAR(violation(x_unsteered), at_end, 1e-6 * at_end);
  std::mt19937 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::VectorXd move(x.size());
    for (Eigen::Index j = 0; j < move.size(); ++j) move[j] = normal(rng);
    const Eigen::VectorXd y = (x + 1e-4 * move.normalized()).cwiseMax(0.0);
    EXPECT_GE(violation(y), at_end - 1e-9) << "trial " << trial;
  }
}

TEST(SequentialLp, RowsGivenAtTheStartAreNotEvaluatedAgainAndComeBackAtTheEnd) {
  // An exchange round starts where the last ended: the rows at its start are handed in instead of
  // evaluated. The same steps to the bit, one evaluation fewer, and the rows handed back are those
  // at the returned point.
  const Problem problem;
  const fpd::SequentialLpLinearPart linear{problem.lp, {static_cast<std::size_t>(Problem::kReserveRows)}, 1e-6};
  int evaluations = 0;
  const fpd::NonlinearRows counted = [&](const Eigen::VectorXd& x, bool jacobian) {
    ++evaluations;
    return problem.rows(x, jacobian);
  };
  auto solve = [&](fpd::BoundRowsAt* given, Eigen::VectorXd& x) {
    double radius = 0.1;
    flatsos::planner::SequentialLpBasis basis;
    evaluations = 0;
    return fpd::solve_by_sequential_lp(linear, counted, x, radius, basis, {}, given);
  };
  Eigen::VectorXd x_own = Eigen::VectorXd::Zero(Problem::kVariables), x_given = x_own;
  const fpd::SequentialLpOutcome own = solve(nullptr, x_own);
  const int own_evaluations = evaluations;
  fpd::BoundRowsAt rows = problem.rows(x_given, true);
  const fpd::SequentialLpOutcome given = solve(&rows, x_given);
  ASSERT_TRUE(own.converged && given.converged) << own.failure << given.failure;
  EXPECT_EQ(given.iterations, own.iterations);
  EXPECT_EQ(x_given, x_own);
  EXPECT_EQ(evaluations, own_evaluations - 1);
  const fpd::BoundRowsAt at_end = problem.rows(x_given, true);
  EXPECT_EQ(rows.value, at_end.value);
  ASSERT_EQ(rows.jacobian.size(), at_end.jacobian.size());
  for (std::size_t k = 0; k < rows.jacobian.size(); ++k) EXPECT_EQ(rows.jacobian[k].value(), at_end.jacobian[k].value());
}

TEST(SequentialLp, AStepThatACurvingRowBreaksBacksOffToWhereItReachesZero) {
  // Minimize x2 - x1 over x2 >= 0 and 1 - x1 - x1^2 / 2 >= 0 from 0: the first LP step goes to
  // x1 = 1, where the curved row is -0.5. Its quadratic through value, slope and that value is
  // the row itself, so the step backs off to its root sqrt(3) - 1 exactly, where halving the
  // box would approach it by halves.
  const fpd::NonlinearRows rows = [](const Eigen::VectorXd& x, bool jacobian) {
    fpd::BoundRowsAt out;
    out.value = {x[1], 1.0 - x[0] - 0.5 * x[0] * x[0]};
    for (const double v : out.value) out.violation += std::max(0.0, -v);
    if (jacobian) {
      out.jacobian.emplace_back(0, 1, 1.0);
      out.jacobian.emplace_back(1, 0, -1.0 - x[0]);
    }
    return out;
  };
  flatsos::planner::LinearProgram lp;
  lp.cost = Eigen::Vector2d(-1.0, 1.0);
  lp.G.resize(0, 2);
  lp.row_lower.resize(0);
  lp.row_upper.resize(0);
  lp.x_lower = Eigen::Vector2d::Constant(-10.0);
  lp.x_upper = Eigen::Vector2d::Constant(10.0);
  const fpd::SequentialLpLinearPart linear{lp, {}, 0.0};
  Eigen::VectorXd x = Eigen::Vector2d::Zero();
  double radius = 5.0;
  flatsos::planner::SequentialLpBasis basis;
  fpd::SequentialLpSettings settings;
  settings.back_off = true;
  const fpd::SequentialLpOutcome out = fpd::solve_by_sequential_lp(linear, rows, x, radius, basis, settings);
  ASSERT_TRUE(out.converged) << out.failure;
  EXPECT_NEAR(x[0], std::sqrt(3.0) - 1.0, 1e-10);
  EXPECT_NEAR(x[1], 0.0, 1e-12);
  EXPECT_LE(out.iterations, 3);
  // Halving instead: the same point, by halves.
  Eigen::VectorXd halved = Eigen::Vector2d::Zero();
  radius = 5.0;
  flatsos::planner::SequentialLpBasis halved_basis;
  const fpd::SequentialLpOutcome by_halves = fpd::solve_by_sequential_lp(linear, rows, halved, radius, halved_basis);
  ASSERT_TRUE(by_halves.converged) << by_halves.failure;
  EXPECT_LT((halved - x).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_GT(by_halves.iterations, 10);
  std::printf("[ measure  ] %d LP steps; halving the box %d\n", out.iterations, by_halves.iterations);
}
