// Newton's method on the last vertex (bounds/vertex_newton.hpp) against the sequential LP on a
// problem of the bounds' shape: where the moved problem keeps its active rows, or rows join the
// vertex, it must end where the sequential LP ends, and everywhere else it must say no rather
// than return another point. And the bound rows it takes from a receding-horizon step's period
// (bounds/point_rows.hpp) against the rows with their whole Jacobian.
#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "bounds/point_rows.hpp"
#include "bounds/vertex_newton.hpp"
#include "flatsos/planner/receding_horizon_step.hpp"
#include "receding_horizon/period_bounds.hpp"
#include "concave_rows_problem.hpp"

namespace fpd = flatsos::planner::detail;
using flatsos::testing::Problem;

namespace {

struct Solved {
  Problem problem;
  Problem::Solved at;
  std::vector<int> vertex;
};

// The problem with rows a hundred times less curved (its optimum a vertex), reserve rows and
// bounds on x that never bind: a vertex of bound rows alone.
Problem loose() {
  Problem p;
  p.lp.row_lower.setConstant(-1e3);
  p.lp.x_lower.setConstant(-1e3);
  p.rows.kappa *= 0.01;
  return p;
}

Solved solve(const Problem& problem) {
  Solved s{problem, problem.solve(true), {}};
  s.vertex = fpd::vertex_rows(s.at.outcome, s.at.x, problem.lp.x_lower);
  return s;
}

// Newton's method on `last`'s vertex for `moved`, from last's optimum (into x; the vertex it ends on into `vertex`).
fpd::VertexNewtonOutcome newton_from(const Solved& last, const Problem& moved, Eigen::VectorXd& x,
                                     std::vector<int>* vertex = nullptr) {
  const fpd::SequentialLpLinearPart linear{moved.lp, {static_cast<std::size_t>(Problem::kReserveRows)}, 1e-6};
  x = last.at.x;
  std::vector<int> active = last.vertex;
  const fpd::NonlinearRows rows = moved.rows;
  fpd::VertexRowsOf vertex_rows(rows, moved.rows(x, true));
  const fpd::VertexNewtonOutcome out = fpd::solve_on_vertex(linear, vertex_rows, active, x);
  if (vertex) *vertex = active;
  return out;
}

// Expects x and its vertex to be where the sequential LP ends on `moved` from the start (the
// same point to 1e-8 and the same active rows); returns its LP steps.
int expect_the_sequential_lps_end(const Problem& moved, const Eigen::VectorXd& x, std::vector<int> vertex) {
  const Problem::Solved slp = moved.solve(true);
  EXPECT_TRUE(slp.outcome.converged) << slp.outcome.failure;
  EXPECT_LT((x - slp.x).cwiseAbs().maxCoeff(), 1e-8) << x.transpose() << "\n" << slp.x.transpose();
  std::vector<int> slp_vertex = fpd::vertex_rows(slp.outcome, slp.x, moved.lp.x_lower);
  std::sort(slp_vertex.begin(), slp_vertex.end());
  std::sort(vertex.begin(), vertex.end());
  EXPECT_EQ(vertex, slp_vertex);
  return slp.outcome.iterations;
}

}  // namespace

TEST(VertexNewton, TheSequentialLpsOptimumIsAVertexOfItsBoundRows) {
  const Solved s = solve(loose());
  ASSERT_TRUE(s.at.outcome.converged) << s.at.outcome.failure;
  ASSERT_EQ(s.vertex.size(), static_cast<std::size_t>(Problem::kVariables));
  const fpd::BoundRowsAt at = s.problem.rows(s.at.x, false);
  for (const int row : s.vertex) EXPECT_LT(std::abs(at.value[static_cast<std::size_t>(row)]), 1e-9) << "row " << row;
}

TEST(VertexNewton, AMovedProblemThatKeepsItsActiveRowsEndsWhereTheSequentialLpEnds) {
  const Solved last = solve(loose());
  ASSERT_EQ(last.vertex.size(), static_cast<std::size_t>(Problem::kVariables));
  Problem moved = loose();
  moved.rows.b.array() += 0.01;  // every row a little tighter: the optimum moves, its rows stay
  Eigen::VectorXd x;
  const fpd::VertexNewtonOutcome newton = newton_from(last, moved, x);
  ASSERT_TRUE(newton.solved) << newton.why_not;
  EXPECT_TRUE(newton.converged);
  EXPECT_GE(newton.iterations, 2);
  EXPECT_LE(newton.iterations, 4);
  const Problem::Solved slp = moved.solve(true);
  ASSERT_TRUE(slp.outcome.converged) << slp.outcome.failure;
  EXPECT_LT((x - slp.x).cwiseAbs().maxCoeff(), 1e-8) << x.transpose() << "\n" << slp.x.transpose();
  EXPECT_GT((x - last.at.x).cwiseAbs().maxCoeff(), 1e-4) << "the problem did not move";
  std::cout << "[ measure  ] " << newton.iterations << " Newton steps; the sequential LP from the start: "
            << slp.outcome.iterations << " LP steps\n";
}

TEST(VertexNewton, ARowThatNowBindsJoinsTheVertexWhereTheSequentialLpFindsIt) {
  const Solved last = solve(loose());
  ASSERT_EQ(last.vertex.size(), static_cast<std::size_t>(Problem::kVariables));
  // A row off the vertex raised until it cuts the vertex off: the optimum moves to a vertex
  // with that row in it.
  const fpd::BoundRowsAt at = last.problem.rows(last.at.x, false);
  std::size_t off = 0;
  while (std::find(last.vertex.begin(), last.vertex.end(), static_cast<int>(off)) != last.vertex.end()) ++off;
  Problem moved = loose();
  moved.rows.b[static_cast<Eigen::Index>(off)] += at.value[off] + 0.05;
  Eigen::VectorXd x;
  std::vector<int> vertex;
  const fpd::VertexNewtonOutcome newton = newton_from(last, moved, x, &vertex);
  ASSERT_TRUE(newton.solved) << newton.why_not;
  EXPECT_GE(newton.pivots, 1);
  EXPECT_NE(std::find(vertex.begin(), vertex.end(), static_cast<int>(off)), vertex.end()) << "the raised row is not in the vertex";
  const int lp_steps = expect_the_sequential_lps_end(moved, x, vertex);
  std::cout << "[ measure  ] " << newton.iterations << " Newton steps, " << newton.pivots
            << " pivots; the sequential LP from the start: " << lp_steps << " LP steps\n";
}

TEST(VertexNewton, AVertexThatBreaksAReserveRowIsNotTaken) {
  const Solved last = solve(loose());
  ASSERT_EQ(last.vertex.size(), static_cast<std::size_t>(Problem::kVariables));
  Problem moved = loose();
  moved.rows.b.array() += 0.01;  // the same move as above
  moved.lp.row_lower[0] = moved.lp.G.row(0).dot(last.at.x) + 1.0;  // a reserve row the moved vertex cannot meet
  Eigen::VectorXd x;
  const fpd::VertexNewtonOutcome newton = newton_from(last, moved, x);
  EXPECT_TRUE(newton.converged);
  EXPECT_FALSE(newton.solved);
  EXPECT_NE(newton.why_not.find("reserve row"), std::string::npos) << newton.why_not;
}

TEST(VertexNewton, ReserveRowsAndBoundsOnThetaJoinTheVertexAsRowsDo) {
  // The move above, a reserve row raised above the vertex and one entry's lower bound above its
  // value there: with the linear rows beside the bound rows both join the vertex, which ends
  // where the sequential LP ends.
  const Solved last = solve(loose());
  ASSERT_EQ(last.vertex.size(), static_cast<std::size_t>(Problem::kVariables));
  Problem moved = loose();
  moved.rows.b.array() += 0.01;
  moved.lp.row_lower[0] = moved.lp.G.row(0).dot(last.at.x) + 0.05;
  moved.lp.x_lower[2] = last.at.x[2] + 0.02;
  const fpd::SequentialLpLinearPart linear{moved.lp, {static_cast<std::size_t>(Problem::kReserveRows)}, 1e-6};
  const fpd::NonlinearRows rows = moved.rows;
  Eigen::VectorXd x = last.at.x;
  fpd::VertexRowsOf bound_rows(rows, moved.rows(x, true));
  fpd::WithLinearRows with_linear(bound_rows, moved.lp);
  with_linear.evaluate(x, true);
  std::vector<int> vertex = last.vertex;
  const fpd::VertexNewtonOutcome newton = fpd::solve_on_vertex(linear, with_linear, vertex, x);
  ASSERT_TRUE(newton.solved) << newton.why_not;
  const int reserve_row = Problem::kRows, theta_bound = Problem::kRows + Problem::kReserveRows + 2;
  EXPECT_NE(std::find(vertex.begin(), vertex.end(), reserve_row), vertex.end());
  EXPECT_NE(std::find(vertex.begin(), vertex.end(), theta_bound), vertex.end());
  expect_the_sequential_lps_end(moved, x, vertex);
}

TEST(VertexNewton, AVertexWhereTheCostStillFallsIsNotTheOptimum) {
  // The same rows and vertex with the cost reversed: every multiplier negative.
  const Solved last = solve(loose());
  ASSERT_EQ(last.vertex.size(), static_cast<std::size_t>(Problem::kVariables));
  Problem reversed = loose();
  reversed.lp.cost = -reversed.lp.cost;
  Eigen::VectorXd x;
  const fpd::VertexNewtonOutcome newton = newton_from(last, reversed, x);
  EXPECT_TRUE(newton.converged);
  EXPECT_FALSE(newton.solved);
  EXPECT_EQ(newton.iterations, 0);  // it starts on the vertex
  EXPECT_NE(newton.why_not.find("multiplier is negative"), std::string::npos) << newton.why_not;
}

TEST(VertexNewton, AnActiveSetOfTheWrongSizeOrRowsIsRefused) {
  Solved last = solve(loose());
  ASSERT_EQ(last.vertex.size(), static_cast<std::size_t>(Problem::kVariables));
  Eigen::VectorXd x;
  Solved short_set = last;
  short_set.vertex.pop_back();
  fpd::VertexNewtonOutcome newton = newton_from(short_set, last.problem, x);
  EXPECT_FALSE(newton.converged);
  EXPECT_EQ(x, last.at.x);
  Solved repeated = last;
  repeated.vertex.back() = repeated.vertex.front();
  newton = newton_from(repeated, last.problem, x);
  EXPECT_FALSE(newton.converged);
  EXPECT_NE(newton.why_not.find("twice"), std::string::npos) << newton.why_not;
  Solved beyond = last;
  beyond.vertex.back() = Problem::kRows;
  EXPECT_FALSE(newton_from(beyond, last.problem, x).converged);
}

// The bound rows of a receding-horizon step's period kept with gradients in each point's force
// jets (PointRows) are the rows of evaluate_rows: the same values, each row's gradient in theta
// the Jacobian's row, and a step's change of every row the Jacobian times the step.
TEST(PointRows, AreTheBoundRowsWithTheirJacobianInTheta) {
  const auto model =
      flatsos::plugin::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) + "/models/seated_knee_r.json");
  const flatsos::planner::FlatOutputMap flat(model);
  flatsos::plugin::ModelWorkspace ws = flat.makeWorkspace();
  flatsos::planner::RecedingHorizonOptions o;
  o.target_q_rad = Eigen::VectorXd::Constant(1, 0.35);
  o.reserves_N = Eigen::VectorXd::Constant(13, 1.0);
  const auto step = flatsos::planner::plan_receding_horizon_step(flat, ws, Eigen::VectorXd::Constant(1, 1.05),
                                                                Eigen::VectorXd::Constant(1, -1.0), o);
  ASSERT_EQ(step.status, flatsos::planner::SolveStatus::Solved) << step.message;
  ASSERT_TRUE(step.bounds_imposed);
  const std::vector<fpd::BoundPoint> points = fpd::period_points(flat, o.excitation_bounds, step);
  const Eigen::VectorXd a_min = fpd::activation_minima(flat, 0.0);
  fpd::PointRows point_rows(flat, points, a_min, fpd::kSampleMargin);
  const Eigen::Index p = step.alpha().size();
  Eigen::VectorXd d = Eigen::VectorXd::LinSpaced(p, -1.0, 2.0), g(p);
  std::vector<double> change;
  for (const double scale : {0.5, 1.0, 1.5}) {
    const Eigen::VectorXd x = scale * step.alpha();
    const fpd::BoundRowsAt at = fpd::evaluate_rows(flat, points, a_min, x, true, fpd::kSampleMargin);
    const fpd::JacobianByRow jacobian(at);
    point_rows.evaluate(x, true);
    ASSERT_EQ(point_rows.values(), at.value);
    EXPECT_DOUBLE_EQ(point_rows.violation(), at.violation);
    point_rows.change(d, change);
    ASSERT_EQ(change.size(), at.value.size());
    Eigen::VectorXd expected(p);
    for (std::size_t row = 0; row < at.value.size(); ++row) {
      jacobian.copy_row(row, expected);
      point_rows.gradient(row, g);
      EXPECT_LE((g - expected).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + expected.cwiseAbs().maxCoeff())) << "row " << row;
      EXPECT_NEAR(change[row], expected.dot(d), 1e-12 * (1.0 + expected.cwiseAbs().sum() * 2.0)) << "row " << row;
    }
  }
  // Evaluated without gradients, the rows have none to give: asking is a programming error.
  point_rows.evaluate(step.alpha(), false);
  EXPECT_THROW(point_rows.gradient(0, g), std::logic_error);
  EXPECT_THROW(point_rows.change(d, change), std::logic_error);
}
