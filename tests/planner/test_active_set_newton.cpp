// Newton's method on the last vertex (bounds/active_set_newton.hpp) against the sequential LP on a
// problem of the bounds' shape: where the moved problem keeps its active rows, or rows join the
// vertex, it must end where the sequential LP ends, and everywhere else it must say no rather
// than return another point. And the bound rows it takes from a receding-horizon step's period
// (bounds/point_rows.hpp) against the rows with their whole Jacobian.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "bounds/point_rows.hpp"
#include "bounds/active_set_newton.hpp"
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
  s.vertex = fpd::active_rows(s.at.outcome, s.at.x, problem.lp.x_lower);
  return s;
}

// Newton's method on `last`'s vertex for `moved`, from last's optimum (into x; the vertex it ends on into `vertex`).
fpd::ActiveSetNewtonOutcome newton_from(const Solved& last, const Problem& moved, Eigen::VectorXd& x,
                                     std::vector<int>* vertex = nullptr) {
  const fpd::SequentialLpLinearPart linear{moved.lp, {static_cast<std::size_t>(Problem::kReserveRows)}, 1e-6};
  x = last.at.x;
  std::vector<int> active = last.vertex;
  const fpd::NonlinearRows rows = moved.rows;
  fpd::ActiveSetRowsOf at_x(rows, x);
  const fpd::ActiveSetNewtonOutcome out = fpd::solve_on_active_set(linear, at_x, active, x);
  if (vertex) *vertex = active;
  return out;
}

// Expects x and its vertex to be where the sequential LP ends on `moved` from the start (the
// same point to 1e-8 and the same active rows); returns its LP steps.
int expect_the_sequential_lps_end(const Problem& moved, const Eigen::VectorXd& x, std::vector<int> vertex) {
  const Problem::Solved slp = moved.solve(true);
  EXPECT_TRUE(slp.outcome.converged) << slp.outcome.failure;
  EXPECT_LT((x - slp.x).cwiseAbs().maxCoeff(), 1e-8) << x.transpose() << "\n" << slp.x.transpose();
  std::vector<int> slp_vertex = fpd::active_rows(slp.outcome, slp.x, moved.lp.x_lower);
  std::sort(slp_vertex.begin(), slp_vertex.end());
  std::sort(vertex.begin(), vertex.end());
  EXPECT_EQ(vertex, slp_vertex);
  return slp.outcome.iterations;
}

}  // namespace

TEST(ActiveSetNewton, TheSequentialLpsOptimumIsAVertexOfItsBoundRows) {
  const Solved s = solve(loose());
  ASSERT_TRUE(s.at.outcome.converged) << s.at.outcome.failure;
  ASSERT_EQ(s.vertex.size(), static_cast<std::size_t>(Problem::kVariables));
  const fpd::BoundRowsAt at = s.problem.rows(s.at.x, false);
  for (const int row : s.vertex) EXPECT_LT(std::abs(at.value[static_cast<std::size_t>(row)]), 1e-9) << "row " << row;
}

TEST(ActiveSetNewton, AMovedProblemThatKeepsItsActiveRowsEndsWhereTheSequentialLpEnds) {
  const Solved last = solve(loose());
  ASSERT_EQ(last.vertex.size(), static_cast<std::size_t>(Problem::kVariables));
  Problem moved = loose();
  moved.rows.b.array() += 0.01;  // every row a little tighter: the optimum moves, its rows stay
  Eigen::VectorXd x;
  const fpd::ActiveSetNewtonOutcome newton = newton_from(last, moved, x);
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

TEST(ActiveSetNewton, ARowThatNowBindsJoinsTheVertexWhereTheSequentialLpFindsIt) {
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
  const fpd::ActiveSetNewtonOutcome newton = newton_from(last, moved, x, &vertex);
  ASSERT_TRUE(newton.solved) << newton.why_not;
  EXPECT_GE(newton.pivots, 1);
  EXPECT_NE(std::find(vertex.begin(), vertex.end(), static_cast<int>(off)), vertex.end()) << "the raised row is not in the vertex";
  const int lp_steps = expect_the_sequential_lps_end(moved, x, vertex);
  std::cout << "[ measure  ] " << newton.iterations << " Newton steps, " << newton.pivots
            << " pivots; the sequential LP from the start: " << lp_steps << " LP steps\n";
}

TEST(ActiveSetNewton, AVertexThatBreaksAReserveRowIsNotTaken) {
  const Solved last = solve(loose());
  ASSERT_EQ(last.vertex.size(), static_cast<std::size_t>(Problem::kVariables));
  Problem moved = loose();
  moved.rows.b.array() += 0.01;  // the same move as above
  moved.lp.row_lower[0] = moved.lp.G.row(0).dot(last.at.x) + 1.0;  // a reserve row the moved vertex cannot meet
  Eigen::VectorXd x;
  const fpd::ActiveSetNewtonOutcome newton = newton_from(last, moved, x);
  EXPECT_TRUE(newton.converged);
  EXPECT_FALSE(newton.solved);
  EXPECT_NE(newton.why_not.find("reserve row"), std::string::npos) << newton.why_not;
}

TEST(ActiveSetNewton, ReserveRowsAndBoundsOnThetaJoinTheVertexAsRowsDo) {
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
  fpd::ActiveSetRowsOf bound_rows(rows, x);
  fpd::WithLinearRows with_linear(bound_rows, moved.lp);
  with_linear.evaluate(x, true);
  std::vector<int> vertex = last.vertex;
  const fpd::ActiveSetNewtonOutcome newton = fpd::solve_on_active_set(linear, with_linear, vertex, x);
  ASSERT_TRUE(newton.solved) << newton.why_not;
  const int reserve_row = Problem::kRows, theta_bound = Problem::kRows + Problem::kReserveRows + 2;
  EXPECT_NE(std::find(vertex.begin(), vertex.end(), reserve_row), vertex.end());
  EXPECT_NE(std::find(vertex.begin(), vertex.end(), theta_bound), vertex.end());
  expect_the_sequential_lps_end(moved, x, vertex);
}

TEST(ActiveSetNewton, AVertexWhereTheCostStillFallsIsNotTheOptimum) {
  // The same rows and vertex with the cost reversed: every multiplier negative.
  const Solved last = solve(loose());
  ASSERT_EQ(last.vertex.size(), static_cast<std::size_t>(Problem::kVariables));
  Problem reversed = loose();
  reversed.lp.cost = -reversed.lp.cost;
  Eigen::VectorXd x;
  const fpd::ActiveSetNewtonOutcome newton = newton_from(last, reversed, x);
  EXPECT_TRUE(newton.converged);
  EXPECT_FALSE(newton.solved);
  EXPECT_EQ(newton.iterations, 0);  // it starts on the vertex
  EXPECT_NE(newton.why_not.find("multiplier is negative"), std::string::npos) << newton.why_not;
}

TEST(ActiveSetNewton, AnActiveSetOfTheWrongSizeOrRowsIsRefused) {
  Solved last = solve(loose());
  ASSERT_EQ(last.vertex.size(), static_cast<std::size_t>(Problem::kVariables));
  Eigen::VectorXd x;
  Solved empty = last;
  empty.vertex.clear();
  fpd::ActiveSetNewtonOutcome newton = newton_from(empty, last.problem, x);
  EXPECT_FALSE(newton.converged);
  EXPECT_EQ(x, last.at.x);
  Solved too_many = last;
  too_many.vertex.push_back(Problem::kRows - 1);
  EXPECT_FALSE(newton_from(too_many, last.problem, x).converged);
  Solved repeated = last;
  repeated.vertex.back() = repeated.vertex.front();
  newton = newton_from(repeated, last.problem, x);
  EXPECT_FALSE(newton.converged);
  EXPECT_NE(newton.why_not.find("twice"), std::string::npos) << newton.why_not;
  Solved beyond = last;
  beyond.vertex.back() = Problem::kRows;
  EXPECT_FALSE(newton_from(beyond, last.problem, x).converged);
}

TEST(ActiveSetNewton, AVertexMissingARowFindsItAlongTheFreeDirection) {
  // One row short of the vertex, at the vertex: the cost falls along the free direction until
  // the missing row stops it, which joins again where it was.
  const Solved last = solve(loose());
  ASSERT_EQ(last.vertex.size(), static_cast<std::size_t>(Problem::kVariables));
  Solved short_set = last;
  const int dropped = short_set.vertex.back();
  short_set.vertex.pop_back();
  Eigen::VectorXd x;
  std::vector<int> active;
  const fpd::ActiveSetNewtonOutcome newton = newton_from(short_set, last.problem, x, &active);
  ASSERT_TRUE(newton.solved) << newton.why_not;
  EXPECT_GE(newton.pivots, 1);
  EXPECT_NE(std::find(active.begin(), active.end(), dropped), active.end());
  EXPECT_LT((x - last.at.x).cwiseAbs().maxCoeff(), 1e-9);
}

// The multipliers y that fit cost = J^T y best, J the `active` rows' gradients at x, and the
// residual of that fit (0 at a KKT point on those rows).
Eigen::MatrixXd active_gradients(const Problem& problem, const std::vector<int>& active, const Eigen::VectorXd& x) {
  const fpd::NonlinearRows rows = problem.rows;
  const fpd::ActiveSetRowsOf at_x(rows, x);
  Eigen::MatrixXd J(x.size(), static_cast<Eigen::Index>(active.size()));
  Eigen::VectorXd g(x.size());
  for (std::size_t k = 0; k < active.size(); ++k) {
    at_x.gradient(static_cast<std::size_t>(active[k]), g);
    J.col(static_cast<Eigen::Index>(k)) = g;
  }
  return J;
}
Eigen::VectorXd least_squares_multipliers(const Problem& problem, const std::vector<int>& active, const Eigen::VectorXd& x) {
  return active_gradients(problem, active, x).colPivHouseholderQr().solve(problem.lp.cost);
}
double kkt_residual(const Problem& problem, const std::vector<int>& active, const Eigen::VectorXd& x) {
  return (active_gradients(problem, active, x) * least_squares_multipliers(problem, active, x) - problem.lp.cost).norm();
}

// Rows as curved as the sequential LP's own test problem: its optimum has one row fewer than
// theta has entries, where the sequential LP converges linearly (50 LP steps).
Problem curved() {
  Problem p = loose();
  p.rows.kappa *= 100.0;
  return p;
}

TEST(ActiveSetNewton, AnOptimumOnCurvedRowsIsReachedAlongTheirFreeDirection) {
  const Solved last = solve(curved());
  ASSERT_TRUE(last.at.outcome.converged) << last.at.outcome.failure;
  ASSERT_EQ(last.vertex.size(), static_cast<std::size_t>(Problem::kVariables - 1));
  Problem moved = curved();
  moved.rows.b.array() += 0.01;
  Eigen::VectorXd x;
  std::vector<int> active;
  const fpd::ActiveSetNewtonOutcome newton = newton_from(last, moved, x, &active);
  ASSERT_TRUE(newton.solved) << newton.why_not;
  EXPECT_EQ(active.size(), last.vertex.size());
  EXPECT_LE(newton.iterations, 5);
  EXPECT_GT((x - last.at.x).cwiseAbs().maxCoeff(), 1e-4) << "the problem did not move";
  // The sequential LP converges linearly here and stops short of stationarity (a KKT residual
  // of 3.5e-5, printed below): Newton's point is checked as a KKT point of its own, on the
  // sequential LP's rows and no costlier than its end.
  const Problem::Solved slp = moved.solve(true);
  ASSERT_TRUE(slp.outcome.converged) << slp.outcome.failure;
  std::vector<int> slp_active = fpd::active_rows(slp.outcome, slp.x, moved.lp.x_lower), sorted = active;
  std::sort(slp_active.begin(), slp_active.end());
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(sorted, slp_active);
  const fpd::BoundRowsAt at_x = moved.rows(x, false);
  for (const int row : active) EXPECT_LT(std::abs(at_x.value[static_cast<std::size_t>(row)]), 1e-10);
  EXPECT_GE(*std::min_element(at_x.value.begin(), at_x.value.end()), -1e-10);
  EXPECT_LT(kkt_residual(moved, active, x), 1e-12);
  EXPECT_GT(least_squares_multipliers(moved, active, x).minCoeff(), 0.0);
  EXPECT_LE(moved.lp.cost.dot(x), moved.lp.cost.dot(slp.x) + 1e-12);
  EXPECT_LT((x - slp.x).cwiseAbs().maxCoeff(), 1e-3);
  std::cout << "[ measure  ] " << newton.iterations << " Newton steps; the sequential LP from the start: "
            << slp.outcome.iterations << " LP steps; KKT residual " << kkt_residual(moved, active, slp.x)
            << " at the sequential LP's end, " << kkt_residual(moved, active, x) << " at Newton's\n";
}

TEST(ActiveSetNewton, AFreeDirectionAlongWhichTheCostCurvesDownEndsOnTheRowThatBlocksIt) {
  // The curved optimum's active rows turned convex: along their free direction the Lagrangian
  // curves down, so no point on those rows alone is a minimum; the cost falls along it until
  // another row blocks it, and the end is a vertex with positive multipliers (a strict local
  // minimum: every direction that keeps its rows >= 0 raises the cost).
  const Solved last = solve(curved());
  ASSERT_EQ(last.vertex.size(), static_cast<std::size_t>(Problem::kVariables - 1));
  Problem convex = curved();
  convex.rows.kappa = -convex.rows.kappa;
  Eigen::VectorXd x;
  std::vector<int> active;
  const fpd::ActiveSetNewtonOutcome newton = newton_from(last, convex, x, &active);
  ASSERT_TRUE(newton.solved) << newton.why_not;
  EXPECT_EQ(active.size(), static_cast<std::size_t>(Problem::kVariables));
  const fpd::BoundRowsAt at_x = convex.rows(x, false);
  for (const int row : active) EXPECT_LT(std::abs(at_x.value[static_cast<std::size_t>(row)]), 1e-10);
  EXPECT_GE(*std::min_element(at_x.value.begin(), at_x.value.end()), -1e-10);
  EXPECT_LT(kkt_residual(convex, active, x), 1e-12);
  EXPECT_GT(least_squares_multipliers(convex, active, x).minCoeff(), 0.0);
}

TEST(ActiveSetNewton, FreeDirectionsThatNoRowBoundsAreRefused) {
  // Five flat rows in six unknowns and nothing else: the cost falls without end along the one
  // direction they leave free.
  Problem flat = loose();
  flat.rows = flatsos::testing::ConcaveRows(5, Problem::kVariables, 7);
  flat.rows.kappa.setZero();
  Solved start;
  start.problem = flat;
  start.at.x = Eigen::VectorXd::Ones(Problem::kVariables);
  start.vertex = {0, 1, 2, 3, 4};
  Eigen::VectorXd x;
  const fpd::ActiveSetNewtonOutcome newton = newton_from(start, flat, x);
  EXPECT_FALSE(newton.solved);
  EXPECT_NE(newton.why_not.find("no row bounds"), std::string::npos) << newton.why_not;
}

TEST(ActiveSetNewton, TheRowsCurvatureIsTheirHessianAlongADirection) {
  // r_i = a_i . x - b_i - kappa_i / 2 |x - c|^2 has the Hessian -kappa_i I.
  const Problem problem = curved();
  const fpd::NonlinearRows rows = problem.rows;
  const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(Problem::kVariables, 0.2, 1.4);
  const Eigen::VectorXd z = Eigen::VectorXd::LinSpaced(Problem::kVariables, -1.0, 0.7);
  fpd::ActiveSetRowsOf at_x(rows, x);
  const std::vector<int> which = {3, 17, 250};
  const Eigen::Vector3d weight(0.5, -2.0, 1.25);
  Eigen::VectorXd curvature;
  at_x.curvature(which, weight, z, curvature);
  double exact = 0.0;
  for (std::size_t k = 0; k < which.size(); ++k) exact -= weight[static_cast<Eigen::Index>(k)] * problem.rows.kappa[which[k]];
  EXPECT_LT((curvature - exact * z).cwiseAbs().maxCoeff(), 1e-8) << curvature.transpose() << "\n" << (exact * z).transpose();
}

namespace {
// A bounded step of the seated knee and its first period's bound points.
struct KneePeriodRows {
  std::shared_ptr<const flatsos::plugin::MusculoskeletalModel> model =
      flatsos::plugin::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) + "/models/seated_knee_r.json");
  flatsos::planner::FlatOutputMap flat{model};
  flatsos::plugin::ModelWorkspace ws = flat.makeWorkspace();
  flatsos::planner::RecedingHorizonOptions o = [] {
    flatsos::planner::RecedingHorizonOptions options;
    options.target_q_rad = Eigen::VectorXd::Constant(1, 0.35);
    options.reserves_N = Eigen::VectorXd::Constant(13, 1.0);
    return options;
  }();
  flatsos::planner::RecedingHorizonStep step = flatsos::planner::plan_receding_horizon_step(
      flat, ws, Eigen::VectorXd::Constant(1, 1.05), Eigen::VectorXd::Constant(1, -1.0), o);
  std::vector<fpd::BoundPoint> points = fpd::period_points(flat, o.excitation_bounds, step);
  Eigen::VectorXd a_min = fpd::activation_minima(flat, 0.0);
};
}  // namespace

// The bound rows of a receding-horizon step's period kept with gradients in each point's force
// jets (PointRows) are the rows of evaluate_rows: the same values, each row's gradient in theta
// the Jacobian's row, and a step's change of every row the Jacobian times the step.
TEST(PointRows, AreTheBoundRowsWithTheirJacobianInTheta) {
  KneePeriodRows knee;
  ASSERT_EQ(knee.step.status, flatsos::planner::SolveStatus::Solved) << knee.step.message;
  ASSERT_TRUE(knee.step.bounds_imposed);
  const flatsos::planner::FlatOutputMap& flat = knee.flat;
  const auto& step = knee.step;
  const std::vector<fpd::BoundPoint>& points = knee.points;
  const Eigen::VectorXd& a_min = knee.a_min;
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

// The last evaluation's inverse is point_excitations' at the same alpha, bit for bit, with or
// without gradients; at another alpha, or with a muscle outside its domain, there is none.
TEST(PointRows, KeepTheExcitationsOfTheirLastEvaluation) {
  KneePeriodRows knee;
  ASSERT_EQ(knee.step.status, flatsos::planner::SolveStatus::Solved) << knee.step.message;
  fpd::PointRows point_rows(knee.flat, knee.points, knee.a_min, fpd::kSampleMargin);
  const Eigen::VectorXd& alpha = knee.step.alpha();
  Eigen::MatrixXd n, a, n_direct, a_direct;
  ASSERT_TRUE(fpd::point_excitations(knee.flat, knee.points, alpha, n_direct, a_direct));
  for (const bool gradients : {true, false}) {
    point_rows.evaluate(alpha, gradients);
    ASSERT_TRUE(point_rows.inverseAt(alpha, n, a));
    EXPECT_EQ(n, n_direct);
    EXPECT_EQ(a, a_direct);
  }
  EXPECT_GT(n_direct.maxCoeff(), 0.01) << "nothing excited: nothing compared";
  EXPECT_FALSE(point_rows.inverseAt(1.01 * alpha, n, a));
  point_rows.evaluate(-1e6 * Eigen::VectorXd::Ones(alpha.size()), false);  // slack tendons
  EXPECT_FALSE(point_rows.inverseAt(-1e6 * Eigen::VectorXd::Ones(alpha.size()), n, a));
}

// A bound row's curvature along z from its force jets (PointRows) against second differences of
// the row's values along z, and against central differences of the whole Jacobian (ActiveSetRowsOf).
TEST(PointRows, CurveAsTheirValuesDoAlongADirection) {
  KneePeriodRows knee;
  ASSERT_EQ(knee.step.status, flatsos::planner::SolveStatus::Solved) << knee.step.message;
  const flatsos::planner::FlatOutputMap& flat = knee.flat;
  const auto& step = knee.step;
  const std::vector<fpd::BoundPoint>& points = knee.points;
  const Eigen::VectorXd& a_min = knee.a_min;
  fpd::PointRows point_rows(flat, points, a_min, fpd::kSampleMargin);
  const fpd::NonlinearRows rows = fpd::bound_rows_of(flat, points, a_min, fpd::kSampleMargin);
  const Eigen::VectorXd x = step.alpha();
  const Eigen::Index p = x.size();
  const Eigen::VectorXd z = Eigen::VectorXd::LinSpaced(p, -1.0, 2.0).normalized();
  point_rows.evaluate(x, true);
  fpd::ActiveSetRowsOf whole(rows, x);
  const double h = 1e-3 * (1.0 + x.cwiseAbs().maxCoeff());
  const fpd::BoundRowsAt plus = rows(x + h * z, false), minus = rows(x - h * z, false);
  int checked = 0;
  double largest = 0.0;
  for (std::size_t row = 0; row < point_rows.values().size(); row += 7) {
    const double v = point_rows.values()[row];
    if (std::abs(v) >= 0.9 || std::abs(plus.value[row]) >= 0.9 || std::abs(minus.value[row]) >= 0.9) continue;  // log-compressed there
    const std::vector<int> one = {static_cast<int>(row)};
    Eigen::VectorXd from_jets, from_jacobian;
    point_rows.curvature(one, Eigen::VectorXd::Ones(1), z, from_jets);
    whole.curvature(one, Eigen::VectorXd::Ones(1), z, from_jacobian);
    const double second_difference = (plus.value[row] - 2.0 * v + minus.value[row]) / (h * h);
    const double scale = 1e-9 + std::abs(second_difference);
    EXPECT_NEAR(z.dot(from_jets), second_difference, 1e-3 * scale) << "row " << row;
    EXPECT_LE((from_jets - from_jacobian).cwiseAbs().maxCoeff(), 1e-6 * (1e-12 + from_jets.cwiseAbs().maxCoeff())) << "row " << row;
    ++checked;
    largest = std::max(largest, std::abs(second_difference));
  }
  EXPECT_GE(checked, 20);
  EXPECT_GT(largest, 1e-6) << "the rows do not curve: nothing tested";
  std::cout << "[ measure  ] " << checked << " rows checked, largest curvature " << largest << " per N^2\n";
}
