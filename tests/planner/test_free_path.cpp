// The joint path as a variable (OpenLoopOptions::free_path). V(c), the bounded plan's cost along
// the path of c at fixed time points, has the gradient its multipliers give (finite-difference
// twin); the optimized path's plan keeps every bound on a 3001-point grid, meets the reserves, is
// certified, costs far less than the prescribed path's, and no small move of the path lowers V;
// a torque model too coarse for the optimized path is refined; bad options are named.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "bounds/bound_rows.hpp"
#include "executable_plan.hpp"
#include "flatsos/planner/effort.hpp"
#include "flatsos/planner/open_loop_study.hpp"
#include "flatsos/planner/rest_state.hpp"
#include "path/free_path.hpp"
#include "path/path_effort.hpp"
#include "path/path_rows.hpp"
#include "path/value_function.hpp"
#include "scenario_fixture.hpp"
#include "sos/bound_points.hpp"
#include "sos/sos_bounds.hpp"
#include "sos/sos_setup.hpp"

namespace fpl = flatsos::planner;
namespace fpd = flatsos::planner::detail;
using flatsos::test::open_loop_options;

namespace {

// Cubic splines on 12 spans at T = 3 s: the bounds are active along the prescribed path.
constexpr double kDuration_s = 3.0;
constexpr int kDegree = 3, kSpans = 12;

class FreePath : public ::testing::Test {
 protected:
  flatsos::test::ArmPlanning arm;
  fpl::MuscleState s0 = flatsos::test::open_loop_initial_state(*arm.model);
  fpl::OpenLoopOptions o = open_loop_options(kDuration_s, kDegree, kSpans);
  fpl::OpenLoopStudyOptions study;
  fpd::SosSettings sos() const { return fpd::sos_settings(o.sos, study.sos); }
  fpd::FreePathSettings free_path() const { return fpd::FreePathSettings(o.free_path, study.free_path); }

  // What plan_open_loop hands the path optimization: the SOS setup along the prescribed path.
  struct Problem {
    fpl::OpenLoopPlan prescribed;
    std::optional<fpd::SosSetup> setup;
    Eigen::MatrixXd initial_q_jet;
    Eigen::VectorXd a_min;
  };
  // The flat outputs' boundary conditions plan_open_loop imposes: the initial state's, rest at T.
  fpl::FlatOutputBoundary boundary() const {
    auto ws = arm.flat.makeWorkspace();
    fpl::FlatOutputBoundary bc;
    bc.initial = arm.flat.forward(ws, s0).Y;
    bc.terminal = Eigen::MatrixXd::Zero(arm.flat.numFlatOutputs(), 2);
    bc.terminal_first_order = 1;
    return bc;
  }
  Problem problem() {
    Problem p;
    p.prescribed = fpl::plan_open_loop(arm.flat, s0, o, study);
    auto ws = arm.flat.makeWorkspace();
    p.setup.emplace(fpd::set_up_sos_program(arm.flat, p.prescribed.torque, o.duration_s, boundary(), o.reserves_N, sos()));
    p.initial_q_jet = arm.flat.forward(ws, s0).q;
    p.a_min = fpd::activation_minima(arm.flat, o.sos.bounds.min_activation);
    return p;
  }

  fpd::PathValue value(const Problem& p, const std::vector<double>& times, const Eigen::VectorXd& c,
                       const Eigen::VectorXd& theta) const {
    return fpd::path_value(*p.setup, arm.flat, p.initial_q_jet, o.target_q_rad, o.reserves_N, p.a_min, free_path(), times, c,
                           theta);
  }

  // The squared-excitation effort on 24 spans in 1.5 s: the problem, and free-path settings that
  // minimize that effort (they point into `effort`, which the case owns).
  struct SquaredEffortCase {
    Problem p;
    std::shared_ptr<const fpl::Effort> effort;
    fpd::FreePathSettings settings;
  };
  SquaredEffortCase squaredEffortCase() {
    o = open_loop_options(1.5, kDegree, 24);
    SquaredEffortCase k{problem(), fpl::effort_named("excitation_squared"), free_path()};
    k.settings.effort = k.effort.get();
    return k;
  }

  static std::vector<double> uniform_times(double T, int count) {
    std::vector<double> t;
    for (int i = 0; i <= count; ++i) t.push_back(T * i / count);
    return t;
  }
};

}  // namespace

TEST_F(FreePath, TheValuesGradientIsTheMultipliersTimesTheRowsDerivatives) {
  // At T = 1.5 s on 24 spans the bound rows are active along the prescribed path: both kinds of
  // rows carry multipliers.
  o = open_loop_options(1.5, kDegree, 24);
  const Problem p = problem();
  ASSERT_EQ(p.prescribed.status, fpl::SolveStatus::Solved) << p.prescribed.message;
  ASSERT_TRUE(p.prescribed.sos.bounds_imposed);
  Eigen::VectorXd c = fpd::path_coefficients(*p.setup, p.prescribed.path, p.initial_q_jet, o.target_q_rad, free_path());
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> move(-0.01, 0.01);
  for (Eigen::Index i = 0; i < c.size(); ++i) c[i] += move(rng);  // generic: away from V's kinks
  const std::vector<double> times = uniform_times(1.5, 48);
  const fpd::PathValue at = value(p, times, c, fpd::theta_of(*p.setup, *p.prescribed.Y));
  ASSERT_TRUE(at.ok) << at.failure;
  EXPECT_GT(at.active_bound_rows, 0);
  EXPECT_GT(at.active_reserve_rows, 0);
  ASSERT_EQ(at.gradient.size(), c.size());
  EXPECT_GT(at.gradient.norm(), 1.0);  // N s per rad: the path matters
  const double h = 1e-4;
  for (Eigen::Index i = 0; i < c.size(); ++i) {
    auto V = [&](double step) {
      Eigen::VectorXd moved = c;
      moved[i] += step;
      const fpd::PathValue v = value(p, times, moved, at.theta);
      EXPECT_TRUE(v.ok) << v.failure;
      return v.cost_N_s;
    };
    const double d1 = (V(h) - V(-h)) / (2 * h), d2 = (V(2 * h) - V(-2 * h)) / (4 * h);
    // Truncation estimated from the two steps; the SLP's convergence (1e-9 of V) over the step.
    const double tolerance = 10.0 * (std::abs(d2 - d1) / 3.0 + 1e-9 * at.cost_N_s / h) + 1e-3;
    EXPECT_NEAR(at.gradient[i], d1, tolerance) << "coefficient " << i;
  }
}

// With a nonlinear effort V(c) is the effort's minimum over theta (its sequential QP), and its
// gradient adds the effort's own derivative in c (the forces and lengths at its quadrature points
// move with the path) to the rows' multipliers times their derivatives.
TEST_F(FreePath, TheSquaredEffortsValueHasTheGradientOfItsPathAndItsMultipliers) {
  const SquaredEffortCase k = squaredEffortCase();
  const Problem& p = k.p;
  ASSERT_EQ(p.prescribed.status, fpl::SolveStatus::Solved) << p.prescribed.message;
  const fpd::FreePathSettings& settings = k.settings;
  Eigen::VectorXd c = fpd::path_coefficients(*p.setup, p.prescribed.path, p.initial_q_jet, o.target_q_rad, settings);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> move(-0.01, 0.01);
  for (Eigen::Index i = 0; i < c.size(); ++i) c[i] += move(rng);
  const std::vector<double> times = uniform_times(1.5, 48);
  auto value_at = [&](const Eigen::VectorXd& at_c, const Eigen::VectorXd& theta) {
    return fpd::path_value(*p.setup, arm.flat, p.initial_q_jet, o.target_q_rad, o.reserves_N, p.a_min, settings, times,
                           at_c, theta);
  };
  const fpd::PathValue at = value_at(c, fpd::theta_of(*p.setup, *p.prescribed.Y));
  ASSERT_TRUE(at.ok) << at.failure;
  EXPECT_GT(at.active_bound_rows + at.active_reserve_rows, 0);
  // The linear effort's value along the same path is in N s; this one is in s, far smaller.
  EXPECT_LT(at.cost_N_s, 1.0);
  ASSERT_EQ(at.gradient.size(), c.size());
  EXPECT_GT(at.gradient.norm(), 1e-3);
  const double h = 1e-4;
  for (Eigen::Index i = 0; i < c.size(); ++i) {
    auto V = [&](double step) {
      Eigen::VectorXd moved = c;
      moved[i] += step;
      const fpd::PathValue v = value_at(moved, at.theta);
      EXPECT_TRUE(v.ok) << v.failure;
      return v.cost_N_s;
    };
    const double d1 = (V(h) - V(-h)) / (2 * h), d2 = (V(2 * h) - V(-2 * h)) / (4 * h);
    // Truncation estimated from the two steps; the QP's convergence (1e-10 of V) over the step.
    const double tolerance = 10.0 * (std::abs(d2 - d1) / 3.0 + 1e-10 * at.cost_N_s / h) + 1e-6 * at.gradient.norm();
    EXPECT_NEAR(at.gradient[i], d1, tolerance) << "coefficient " << i;
  }
}

// V's sequential QP starts from the active rows of the evaluation it starts from (a QP started
// from none added thousands of rows one by one): V, its plan and its gradient are those of a
// start without them.
TEST_F(FreePath, TheSquaredEffortsValueFromTheLastEvaluationsRowsIsTheValueFromNone) {
  const SquaredEffortCase k = squaredEffortCase();
  const Problem& p = k.p;
  ASSERT_EQ(p.prescribed.status, fpl::SolveStatus::Solved) << p.prescribed.message;
  const fpd::FreePathSettings& settings = k.settings;
  const auto& effort = k.effort;
  const fpd::PathParameterization P = fpd::parameterize(settings, 1.5, p.initial_q_jet, o.target_q_rad);
  std::vector<fpd::PathPoint> points;
  for (const double t : uniform_times(1.5, 48)) points.push_back(fpd::make_path_point(*p.setup, arm.flat, P, t));
  const fpd::PathEffort path_effort(*p.setup, arm.flat, P, *effort);
  fpd::ValueFunction V(*p.setup, arm.flat, points, P, o.reserves_N, p.a_min, 200, &path_effort);
  fpd::Evaluation start;
  start.theta = fpd::theta_of(*p.setup, *p.prescribed.Y);
  start.radius = 0.1 * (1.0 + start.theta.cwiseAbs().maxCoeff());
  const Eigen::VectorXd c = fpd::fit_to(P, p.prescribed.path);
  const fpd::Evaluation first = V(c, start);
  ASSERT_TRUE(first.ok) << first.failure;
  EXPECT_FALSE(first.effort_rows.bound.empty() && first.effort_rows.linear.empty());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> move(-0.005, 0.005);
  Eigen::VectorXd moved = c;
  for (Eigen::Index i = 0; i < moved.size(); ++i) moved[i] += move(rng);
  fpd::Evaluation without_rows = first;
  without_rows.effort_rows = {};
  const fpd::Evaluation warm = V(moved, first), cold = V(moved, without_rows);
  ASSERT_TRUE(warm.ok && cold.ok) << warm.failure << cold.failure;
  EXPECT_NEAR(warm.cost_N_s, cold.cost_N_s, 1e-8 * cold.cost_N_s);
  EXPECT_LT((warm.gradient - cold.gradient).norm(), 1e-5 * cold.gradient.norm());
  EXPECT_LT((warm.theta - cold.theta).cwiseAbs().maxCoeff(), 1e-5 * (1.0 + cold.theta.cwiseAbs().maxCoeff()));
  std::printf("QP row changes from the last rows %d, from none %d\n", warm.effort_qp_row_changes,
              cold.effort_qp_row_changes);
  EXPECT_LT(warm.effort_qp_row_changes, cold.effort_qp_row_changes / 2);
}

// The effort along the path as a function of z = (theta, c): its gradient, through the muscle
// inverse, the torque jet and the path lengths, is the twin of central differences of its value.
TEST_F(FreePath, TheEffortAlongThePathHasTheGradientOfItsValue) {
  o = open_loop_options(1.5, kDegree, 24);
  const Problem p = problem();
  ASSERT_EQ(p.prescribed.status, fpl::SolveStatus::Solved) << p.prescribed.message;
  const fpd::PathParameterization P = fpd::parameterize(free_path(), o.duration_s, p.initial_q_jet, o.target_q_rad);
  const fpd::PathVariables v{p.setup->free_coefficients, P.free};
  Eigen::VectorXd z(v.size());
  z << fpd::theta_of(*p.setup, *p.prescribed.Y), fpd::fit_to(P, p.prescribed.path);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> move(-0.01, 0.01);
  for (Eigen::Index i = v.thetas; i < z.size(); ++i) z[i] += move(rng);
  for (const char* name : {"excitation_squared", "activation_cubed", "stress_squared"}) {
    const auto effort = fpl::effort_named(name);
    const fpd::PathEffort E(*p.setup, arm.flat, P, *effort);
    Eigen::VectorXd g;
    ASSERT_TRUE(E.gradient(z, g)) << name;
    auto value = [&](const Eigen::VectorXd& at) {
      double e = 0.0;
      EXPECT_TRUE(E.value(at, e));
      return e;
    };
    double worst = 0.0;
    for (Eigen::Index i = 0; i < z.size(); ++i) {
      const double h = 1e-6 * (1.0 + std::abs(z[i]));
      Eigen::VectorXd up = z, down = z;
      up[i] += h, down[i] -= h;
      worst = std::max(worst, std::abs((value(up) - value(down)) / (2 * h) - g[i]));
    }
    EXPECT_LT(worst, 1e-6 * (1.0 + g.cwiseAbs().maxCoeff())) << name;
  }
}

TEST_F(FreePath, TheRowsHessianIsTheDerivativeOfTheirWeightedGradient) {
  // At T = 1.5 s the bound rows are active: the rows' curvature is large where the plan lives.
  o = open_loop_options(1.5, kDegree, 24);
  const Problem p = problem();
  ASSERT_EQ(p.prescribed.status, fpl::SolveStatus::Solved) << p.prescribed.message;
  const fpd::PathParameterization P = fpd::parameterize(free_path(), o.duration_s, p.initial_q_jet, o.target_q_rad);
  const fpd::PathVariables v{p.setup->free_coefficients, P.free};
  std::vector<fpd::PathPoint> points;
  for (double t : {0.1, 0.37, 0.74, 1.2}) points.push_back(fpd::make_path_point(*p.setup, arm.flat, P, t));
  const fpd::PathRows rows(arm.flat, v, points, o.reserves_N, p.a_min);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0), move(-0.02, 0.02);
  Eigen::VectorXd z(v.size());
  z << fpd::theta_of(*p.setup, *p.prescribed.Y), fpd::fit_to(P, p.prescribed.path);
  for (Eigen::Index i = v.thetas; i < z.size(); ++i) z[i] += move(rng);  // a generic path
  std::vector<double> lambda(static_cast<std::size_t>(rows.rows()));
  for (double& l : lambda) l = unit(rng);
  // The twin: central differences of the exact weighted gradient sum_k lambda_k grad g_k in z.
  auto weighted_gradient = [&](const Eigen::VectorXd& at) {
    Eigen::VectorXd g = Eigen::VectorXd::Zero(at.size());
    for (const auto& t : rows(at, true).jacobian) g[t.col()] += lambda[static_cast<std::size_t>(t.row())] * t.value();
    return g;
  };
  Eigen::MatrixXd twin(z.size(), z.size());
  for (Eigen::Index i = 0; i < z.size(); ++i) {
    const double h = 1e-6 * (1.0 + std::abs(z[i]));
    Eigen::VectorXd up = z, down = z;
    up[i] += h;
    down[i] -= h;
    twin.col(i) = (weighted_gradient(up) - weighted_gradient(down)) / (2.0 * h);
  }
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(z.size(), z.size());
  for (const auto& t : rows.lagrangianHessian(z, lambda)) {
    H(t.row(), t.col()) += t.value();
    if (t.row() != t.col()) H(t.col(), t.row()) += t.value();
  }
  const auto paths = Eigen::seqN(v.thetas, v.paths);
  const double scale = twin.cwiseAbs().maxCoeff();
  ASSERT_GT(twin(paths, paths).cwiseAbs().maxCoeff(), 1e-3 * scale);  // the path's block matters
  EXPECT_LT((H - twin).cwiseAbs().maxCoeff(), 1e-5 * scale);
  EXPECT_LT((H - twin)(paths, paths).cwiseAbs().maxCoeff(), 1e-5 * twin(paths, paths).cwiseAbs().maxCoeff());
  // The pattern holds every entry the values fill.
  const auto pattern = rows.hessianPattern();
  ASSERT_EQ(pattern.size(), rows.lagrangianHessian(z, lambda).size());

  // With the torque jet linearized (the joint Newton method's Hessian) only the path's block
  // changes, and there by the torque jet's curvature, which is not negligible.
  const fpd::PathRows linearized(arm.flat, v, points, o.reserves_N, p.a_min, fpd::TorqueCurvature::Linearized);
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(z.size(), z.size());
  for (const auto& t : linearized.lagrangianHessian(z, lambda)) {
    L(t.row(), t.col()) += t.value();
    if (t.row() != t.col()) L(t.col(), t.row()) += t.value();
  }
  const auto thetas = Eigen::seqN(0, v.thetas), all = Eigen::seqN(0, z.size());
  EXPECT_LT((L - twin)(thetas, all).cwiseAbs().maxCoeff(), 1e-5 * scale);
  EXPECT_GT((L - twin)(paths, paths).cwiseAbs().maxCoeff(), 1e-2 * twin(paths, paths).cwiseAbs().maxCoeff());

  // With a floor for the inverse's curvature (what the joint Newton method uses): muscles whose
  // bound rows' multipliers all stay at or below the floor times the largest add none, exactly as
  // if those multipliers were 0; every other muscle adds its own. Here muscles 0 and 3 at every
  // point get multipliers of at most 0.3, every other muscle one of at least 0.9, all at most 1,
  // under a floor of 0.4.
  const int m = arm.flat.numMuscles();
  std::vector<double> small = lambda, zeroed = lambda;
  for (std::size_t k = 0; k < points.size(); ++k)
    for (int j = 0; j < m; ++j)
      for (int r = 1; r < fpd::PathRows::kRows; ++r) {
        const std::size_t row = (k * static_cast<std::size_t>(m) + static_cast<std::size_t>(j)) * fpd::PathRows::kRows +
                                static_cast<std::size_t>(r);
        if (j == 0 || j == 3) {
          small[row] *= 0.3;
          zeroed[row] = 0.0;
        } else if (r == 1) {
          small[row] = zeroed[row] = std::max(small[row], 0.9);
        }
      }
  auto dense = [&](const fpd::PathRows& of, const std::vector<double>& weights) {
    Eigen::MatrixXd D = Eigen::MatrixXd::Zero(z.size(), z.size());
    for (const auto& t : of.lagrangianHessian(z, weights)) {
      D(t.row(), t.col()) += t.value();
      if (t.row() != t.col()) D(t.col(), t.row()) += t.value();
    }
    return D;
  };
  const fpd::PathRows floored(arm.flat, v, points, o.reserves_N, p.a_min, fpd::TorqueCurvature::Linearized, 0.4);
  const Eigen::MatrixXd with_floor = dense(floored, small), without_them = dense(linearized, zeroed);
  const Eigen::MatrixXd exact = dense(linearized, small);
  EXPECT_LT((with_floor - without_them).cwiseAbs().maxCoeff(), 1e-12 * scale);
  EXPECT_GT((with_floor - exact).cwiseAbs().maxCoeff(), 1e-4 * scale);  // their curvature was there
  // A floor of 0 leaves the Hessian exact; a negative floor is refused.
  const fpd::PathRows zero_floor(arm.flat, v, points, o.reserves_N, p.a_min, fpd::TorqueCurvature::Linearized, 0.0);
  EXPECT_EQ(dense(zero_floor, small), exact);
  EXPECT_THROW(fpd::PathRows(arm.flat, v, points, o.reserves_N, p.a_min, fpd::TorqueCurvature::Linearized, -1.0),
               std::invalid_argument);

  // In place (what Ipopt is given): the same values as the triplets, in their order.
  const fpd::BoundRowsAt at = rows(z, true);
  ASSERT_EQ(at.jacobian.size(), rows.jacobianEntries());
  std::vector<double> values(static_cast<std::size_t>(rows.rows())), only_values(values.size()), jacobian(rows.jacobianEntries());
  rows.evaluateInto(z, values.data(), jacobian.data());
  rows.evaluateInto(z, only_values.data(), nullptr);
  for (std::size_t r = 0; r < values.size(); ++r) {
    EXPECT_EQ(values[r], at.value[r]) << "row " << r;
    EXPECT_NEAR(only_values[r], at.value[r], 1e-12 * (1.0 + std::abs(at.value[r]))) << "row " << r;
  }
  for (std::size_t k = 0; k < jacobian.size(); ++k) EXPECT_EQ(jacobian[k], at.jacobian[k].value()) << "entry " << k;
  const auto triplets = linearized.lagrangianHessian(z, lambda);
  std::vector<double> hessian(triplets.size());
  linearized.lagrangianHessianInto(z, lambda.data(), hessian.data());
  for (std::size_t k = 0; k < hessian.size(); ++k) EXPECT_EQ(hessian[k], triplets[k].value()) << "entry " << k;
  EXPECT_THROW(rows.lagrangianHessian(z, std::vector<double>(3, 1.0)), std::invalid_argument);
}

TEST_F(FreePath, TheOptimizedPathsPlanIsValidCheaperAndNoSmallMoveLowersItsCost) {
  o.free_path.enabled = true;
  const fpl::OpenLoopPlan plan = fpl::plan_open_loop(arm.flat, s0, o, study);
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
  ASSERT_TRUE(plan.free_path.optimized);
  std::cout << "[ measure  ] free path: " << plan.free_path.prescribed_cost_N_s << " -> " << plan.sos.cost_N_s
            << " N s (at its points " << plan.free_path.cost_at_points_N_s << "), " << plan.free_path.path_iterations
            << " steps, " << plan.free_path.evaluations << " evaluations, " << plan.free_path.rounds << " rounds, "
            << plan.free_path.seconds << " s\n";
  EXPECT_LT(plan.sos.cost_N_s, 0.8 * plan.free_path.prescribed_cost_N_s);
  EXPECT_GT(plan.free_path.sequential_lp_iterations, 0);
  EXPECT_EQ(plan.free_path.slp_iterations, plan.free_path.sequential_lp_iterations);  // the deprecated spelling
  // The certified plan along the path costs what the path optimization found at its points.
  EXPECT_NEAR(plan.sos.cost_N_s, plan.free_path.cost_at_points_N_s, 1e-3 * plan.sos.cost_N_s);
  flatsos::test::expect_executable(arm.flat, plan, o.reserves_N);
  // Local optimality on an independent point set (10 per span): no move of 0.01 rad in a random
  // direction lowers V by more than the point sets' difference.
  const Problem p = problem();
  const Eigen::VectorXd c = fpd::path_coefficients(*p.setup, plan.path, p.initial_q_jet, o.target_q_rad, free_path());
  const std::vector<double> times = uniform_times(kDuration_s, 10 * kSpans);
  const fpd::PathValue at = value(p, times, c, fpd::theta_of(*p.setup, *plan.Y));
  ASSERT_TRUE(at.ok) << at.failure;
  EXPECT_NEAR(at.cost_N_s, plan.sos.cost_N_s, 2e-3 * plan.sos.cost_N_s);  // measured 0.16 %: other points
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  double lowest = at.cost_N_s;
  for (int k = 0; k < 8; ++k) {
    Eigen::VectorXd d(c.size());
    for (Eigen::Index i = 0; i < d.size(); ++i) d[i] = normal(rng);
    const fpd::PathValue moved = value(p, times, c + 0.01 * d.normalized(), at.theta);
    if (moved.ok) lowest = std::min(lowest, moved.cost_N_s);
  }
  EXPECT_GE(lowest, at.cost_N_s * (1.0 - 1e-4));
}

TEST_F(FreePath, SpansThatGrowPutTheKnotsWhereTheTransferIsFastAndLowerItsCost) {
  // The low-effort transfer throws the arm up in its first few tenths of a second and settles
  // slowly: with as many coefficients, short spans at the start plan it cheaper.
  o.free_path.enabled = true;
  const fpl::OpenLoopPlan uniform = fpl::plan_open_loop(arm.flat, s0, o, study);
  o.free_path.span_growth = 1.3;
  const fpl::OpenLoopPlan graded = fpl::plan_open_loop(arm.flat, s0, o, study);
  ASSERT_EQ(uniform.status, fpl::SolveStatus::Solved) << uniform.message;
  ASSERT_EQ(graded.status, fpl::SolveStatus::Solved) << graded.message;
  ASSERT_TRUE(graded.path.spline);
  const fpl::BSplineBasis& basis = graded.path.spline->basis();
  ASSERT_EQ(basis.spans(), o.free_path.spans);
  for (int span = 1; span < basis.spans(); ++span)
    EXPECT_NEAR(basis.spanLength(span) / basis.spanLength(span - 1), 1.3, 1e-9) << "span " << span;
  std::cout << "[ measure  ] free path on " << basis.spans() << " spans: uniform " << uniform.sos.cost_N_s
            << " N s, growing by 1.3 " << graded.sos.cost_N_s << " N s\n";
  EXPECT_LT(graded.sos.cost_N_s, uniform.sos.cost_N_s);
  flatsos::test::expect_executable(arm.flat, graded, o.reserves_N);
}

TEST_F(FreePath, TheJointNewtonMethodReachesTheQuasiNewtonMethodsOptimum) {
  // Two independent optimizers of the same problem: BFGS on the plan's value function and Ipopt
  // over the plan and the path together. Both paths' plans must keep the rows on the dense grid
  // and cost the same (the quasi-Newton method stops on V's kinks a little higher).
  const Problem p = problem();
  ASSERT_EQ(p.prescribed.status, fpl::SolveStatus::Solved) << p.prescribed.message;
  const Eigen::VectorXd theta = fpd::theta_of(*p.setup, *p.prescribed.Y);
  // Both with the exchange run until the grid holds.
  auto optimize = [&](fpl::FreePathMethod method, double exchange_relative_tolerance) {
    fpd::FreePathSettings f = free_path();
    f.method = method;
    f.exchange_relative_tolerance = exchange_relative_tolerance;
    return fpd::optimize_joint_path(*p.setup, arm.flat, p.prescribed.path, p.initial_q_jet, o.target_q_rad, theta,
                                    o.reserves_N, p.a_min, f);
  };
  const fpd::FreePathOutcome newton = optimize(fpl::FreePathMethod::JointNewton, 0.0);
  const fpd::FreePathOutcome quasi = optimize(fpl::FreePathMethod::ReducedQuasiNewton, 0.0);
  ASSERT_TRUE(newton.converged) << newton.failure;
  ASSERT_TRUE(quasi.converged) << quasi.failure;
  std::cout << "[ measure  ] free path at its points: joint Newton " << newton.cost_N_s << " N s (" << newton.path_iterations
            << " Ipopt iterations, " << newton.rounds << " rounds), quasi-Newton " << quasi.cost_N_s << " N s ("
            << quasi.path_iterations << " steps)\n";
  EXPECT_LE(newton.worst_bound_excess, study.free_path.tolerance);
  EXPECT_GE(newton.min_reserve_margin_N, -study.free_path.tolerance_N);
  EXPECT_LT(newton.cost_N_s, 0.8 * p.prescribed.sos.cost_N_s);
  EXPECT_NEAR(newton.cost_N_s, quasi.cost_N_s, 2e-3 * quasi.cost_N_s);
  EXPECT_LE(newton.cost_N_s, quasi.cost_N_s * (1.0 + 1e-5));

  // The joint method's exchange ending once a round changes the cost by at most the default
  // fraction of it: fewer rounds, and the cost at the points where the full exchange ends within a
  // few times that tolerance (each later round changes it by less).
  const double settle = fpl::FreePathStudyOptions{}.exchange_relative_tolerance;
  ASSERT_GT(settle, 0.0);
  const fpd::FreePathOutcome settled = optimize(fpl::FreePathMethod::JointNewton, settle);
  ASSERT_TRUE(settled.converged) << settled.failure;
  std::cout << "[ measure  ] settled exchange: " << settled.cost_N_s << " N s in " << settled.rounds << " rounds ("
            << settled.path_iterations << " Ipopt iterations), full: " << newton.cost_N_s << " N s in " << newton.rounds
            << " rounds (" << newton.path_iterations << ")\n";
  EXPECT_LT(settled.rounds, newton.rounds);
  EXPECT_LT(settled.path_iterations, newton.path_iterations);
  EXPECT_NEAR(settled.cost_N_s, newton.cost_N_s, 5.0 * settle * newton.cost_N_s);
}

TEST_F(FreePath, ThePlanAlongTheOptimizedPathStartsFromThePathStagesAndEqualsAColdPlan) {
  // The bounded exchange along the optimized path starts from the path stage's plan and points:
  // the same certified optimum as from the reserves' optimum, in fewer rounds.
  // Cubic splines on 24 spans growing by 1.06, the path on 12 growing by 1.4: along the optimized
  // path the bounds bind (along the fixture's, the reserves' optimum meets them).
  o = flatsos::test::graded_free_path_options(kDuration_s, kDegree, 24);
  study = flatsos::test::joint_newton_study();
  const fpl::OpenLoopPlan plan = fpl::plan_open_loop(arm.flat, s0, o, study);
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
  ASSERT_TRUE(plan.free_path.optimized);
  auto ws = arm.flat.makeWorkspace();
  const fpl::FlatOutputBoundary bc = boundary();
  // The plan's own torque model (refined along the optimized path: 24 pieces cost 219.6 N s
  // there, 10 % above the path stage's, 48 pieces 199.7 N s).
  const fpl::TorqueModel& torque = plan.torque;
  const fpl::MusclesAlongPath muscles{arm.flat, plan.path, ws};
  const fpl::SosProgramResult cold =
      fpl::solve_sos_program(arm.flat, torque, o.duration_s, bc, o.reserves_N, o.sos, study.sos, &muscles);
  ASSERT_EQ(cold.status, fpl::SolveStatus::Solved) << cold.message;
  std::cout << "[ measure  ] along the optimized path: from the path stage " << plan.sos.cost_N_s << " N s in "
            << plan.sos.bound_rounds << " bounded rounds, from the reserves' optimum " << cold.cost_N_s << " N s in "
            << cold.bound_rounds << "; " << plan.free_path.final_torque_pieces << " torque pieces, the path stage "
            << plan.free_path.cost_at_points_N_s << " N s at its points\n";
  EXPECT_TRUE(plan.sos.certified && cold.certified);
  EXPECT_NEAR(plan.sos.cost_N_s, cold.cost_N_s, 1e-6 * cold.cost_N_s);
  EXPECT_LT(plan.sos.bound_rounds, cold.bound_rounds);

  // A warm start that is not the program's is named.
  const fpd::SosSetup program = fpd::set_up_sos_program(arm.flat, torque, o.duration_s, bc, o.reserves_N, sos());
  fpd::BoundsWarmStart warm{fpd::theta_of(program, *plan.Y), {0.5, 4.0}};
  auto rejects = [&](const fpd::BoundsWarmStart& bad, const std::string& what) {
    try {
      fpd::solve_sos_program_from(arm.flat, torque, o.duration_s, bc, o.reserves_N, sos(), muscles, bad);
      ADD_FAILURE() << "accepted " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  rejects(warm, "outside [0, T]");
  warm.times_s = {0.5};
  warm.theta.conservativeResize(warm.theta.size() - 1);
  rejects(warm, "coefficients");
}

TEST_F(FreePath, ThePlanAlongTheOptimizedPathSearchesTheWholeGridFromItsFirstRounds) {
  // From the path stage's plan, the bound violations that only the whole check grid sees are there
  // in the first round (the torque model changed, not the plan). Searched for beside the reserves'
  // dips instead of after them: the same certified plan in fewer rounds.
  // The benchmark's transfer: quintic flat outputs and torque pieces on 48 graded spans.
  const fpl::OpenLoopOptions graded = flatsos::test::graded_free_path_options(kDuration_s, 5, 48);
  o = graded;
  study = flatsos::test::joint_newton_study();
  o.free_path.enabled = false;  // the prescribed path's plan, which the path stage starts from
  const Problem p = problem();
  ASSERT_EQ(p.prescribed.status, fpl::SolveStatus::Solved) << p.prescribed.message;
  const fpd::FreePathOutcome stage =
      fpd::optimize_joint_path(*p.setup, arm.flat, p.prescribed.path, p.initial_q_jet, o.target_q_rad,
                               fpd::theta_of(*p.setup, *p.prescribed.Y), o.reserves_N, p.a_min,
                               fpd::FreePathSettings(graded.free_path, study.free_path));
  ASSERT_TRUE(stage.converged) << stage.failure;
  auto ws = arm.flat.makeWorkspace();
  const fpl::TorqueModel torque = fpl::build_torque_model(arm.flat, ws, stage.path, o.torque, study.torque);
  const fpl::MusclesAlongPath muscles{arm.flat, stage.path, ws};
  auto plan_from_stage = [&](bool whole_grid_every_round) {
    const fpd::BoundsWarmStart warm{stage.theta, stage.times_s, whole_grid_every_round};
    return fpd::solve_sos_program_from(arm.flat, torque, o.duration_s, boundary(), o.reserves_N, sos(), muscles, warm);
  };
  const fpl::SosProgramResult early = plan_from_stage(true), late = plan_from_stage(false);
  ASSERT_EQ(early.status, fpl::SolveStatus::Solved) << early.message;
  ASSERT_EQ(late.status, fpl::SolveStatus::Solved) << late.message;
  std::cout << "[ measure  ] along the optimized path from the path stage: the whole grid searched in every round "
            << early.cost_N_s << " N s in " << early.bound_rounds << " rounds, once the reserves hold " << late.cost_N_s
            << " N s in " << late.bound_rounds << "\n";
  EXPECT_TRUE(early.bounds_imposed && late.bounds_imposed);
  EXPECT_TRUE(early.certified && late.certified);
  EXPECT_NEAR(early.cost_N_s, late.cost_N_s, 1e-6 * late.cost_N_s);
  EXPECT_LT(early.bound_rounds, late.bound_rounds);
  EXPECT_LE(early.max_bound_excess, study.sos.bounds.tolerance);
}

TEST_F(FreePath, TheBoundRowsOfAddedPointsFollowThoseOfThePointsBefore) {
  // An exchange round evaluates only its new points' rows at the theta where the last round ended
  // (fpd::append_rows): the same rows, numbered after the others, as all points' rows at once.
  const Problem p = problem();
  ASSERT_EQ(p.prescribed.status, fpl::SolveStatus::Solved) << p.prescribed.message;
  auto ws = arm.flat.makeWorkspace();
  const fpl::MusclesAlongPath muscles{arm.flat, p.prescribed.path, ws};
  std::vector<fpd::BoundPoint> points;
  for (double t : {0.0, 0.013, 0.4, 1.7, 2.9}) points.push_back(fpd::make_point(*p.setup, muscles, t));
  const Eigen::VectorXd theta = fpd::theta_of(*p.setup, *p.prescribed.Y);
  const fpd::BoundRowsAt all = fpd::evaluate_rows(arm.flat, points, p.a_min, theta, true);
  const std::vector<fpd::BoundPoint> before(points.begin(), points.begin() + 2);
  fpd::BoundRowsAt rows = fpd::evaluate_rows(arm.flat, before, p.a_min, theta, true);
  fpd::append_rows(arm.flat, points, before.size(), p.a_min, theta, true, fpd::kBoundMargin, rows);
  EXPECT_EQ(rows.value, all.value);
  EXPECT_EQ(rows.violation, all.violation);
  ASSERT_EQ(rows.jacobian.size(), all.jacobian.size());
  for (std::size_t k = 0; k < all.jacobian.size(); ++k) {
    EXPECT_EQ(rows.jacobian[k].row(), all.jacobian[k].row()) << "entry " << k;
    EXPECT_EQ(rows.jacobian[k].col(), all.jacobian[k].col()) << "entry " << k;
    EXPECT_EQ(rows.jacobian[k].value(), all.jacobian[k].value()) << "entry " << k;
  }
}

TEST_F(FreePath, ATorqueModelTooCoarseForTheOptimizedPathIsRefinedUntilItsPlanIsSolved) {
  // Quintic flat outputs and torque pieces on 24 graded spans: the optimized path throws the arm
  // faster than 24 cubic torque pieces follow, and the plan along it fails with them. The pieces
  // double until the certified plan costs what the path stage found at its points.
  o = flatsos::test::graded_free_path_options(kDuration_s, 5, 24);
  study = flatsos::test::joint_newton_study();
  study.free_path.max_torque_refinements = 0;
  const fpl::OpenLoopPlan coarse = fpl::plan_open_loop(arm.flat, s0, o, study);
  ASSERT_TRUE(coarse.free_path.optimized);
  EXPECT_NE(coarse.status, fpl::SolveStatus::Solved);
  EXPECT_EQ(coarse.free_path.final_plans, 1);
  EXPECT_EQ(coarse.free_path.final_torque_pieces, 24);

  study.free_path.max_torque_refinements = fpl::FreePathStudyOptions{}.max_torque_refinements;
  const fpl::OpenLoopPlan plan = fpl::plan_open_loop(arm.flat, s0, o, study);
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
  std::cout << "[ measure  ] along the optimized path: " << coarse.message << "; refined to "
            << plan.free_path.final_torque_pieces << " torque pieces (" << plan.free_path.final_plans
            << " plans): " << plan.sos.cost_N_s << " N s, at the path stage's points "
            << plan.free_path.cost_at_points_N_s << "\n";
  EXPECT_GT(plan.free_path.final_plans, 1);
  EXPECT_EQ(plan.free_path.final_torque_pieces, 24 << (plan.free_path.final_plans - 1));
  EXPECT_EQ(plan.torque.pieces.size(), static_cast<std::size_t>(plan.free_path.final_torque_pieces));
  EXPECT_LE(plan.sos.cost_N_s, (1.0 + study.free_path.torque_model_relative_gap) * plan.free_path.cost_at_points_N_s);
  EXPECT_TRUE(plan.sos.certified);
  flatsos::test::expect_executable(arm.flat, plan, o.reserves_N);
}

TEST_F(FreePath, AStartPlanInACoarserNestedBasisLeadsToTheSamePlan) {
  // The prescribed path's plan only starts the path stage. Made on every second breakpoint (12
  // spans growing by 1.06^2 instead of 24 by 1.06), it lies in the flat outputs' splines, costs at
  // least the fine basis' plan (a subspace), and the optimized path's plan is the same.
  o = flatsos::test::graded_free_path_options(kDuration_s, kDegree, 24);
  study = flatsos::test::joint_newton_study();
  auto plan_with = [&](int start_min_spans) {
    fpl::OpenLoopStudyOptions with = study;
    with.free_path.start_min_spans = start_min_spans;
    return fpl::plan_open_loop(arm.flat, s0, o, with);
  };
  const fpl::OpenLoopPlan fine = plan_with(0), coarse = plan_with(12);
  ASSERT_EQ(fine.status, fpl::SolveStatus::Solved) << fine.message;
  ASSERT_EQ(coarse.status, fpl::SolveStatus::Solved) << coarse.message;
  std::cout << "[ measure  ] start plans " << fine.free_path.prescribed_cost_N_s << " N s (24 spans) and "
            << coarse.free_path.prescribed_cost_N_s << " N s (12); plans " << fine.sos.cost_N_s << " and "
            << coarse.sos.cost_N_s << " N s in " << fine.free_path.path_iterations << " and "
            << coarse.free_path.path_iterations << " Ipopt iterations\n";
  EXPECT_EQ(fine.free_path.start_flat_output_spans, 24);
  EXPECT_EQ(coarse.free_path.start_flat_output_spans, 12);
  EXPECT_EQ(coarse.free_path.prescribed_status, "solved");
  EXPECT_GE(coarse.free_path.prescribed_cost_N_s, fine.free_path.prescribed_cost_N_s * (1.0 - 1e-6));
  EXPECT_GT(coarse.free_path.prescribed_cost_N_s, fine.free_path.prescribed_cost_N_s);  // a coarser start indeed
  ASSERT_TRUE(coarse.free_path.optimized);
  EXPECT_NEAR(coarse.sos.cost_N_s, fine.sos.cost_N_s, 1e-5 * fine.sos.cost_N_s);
  EXPECT_EQ(coarse.Y->basis().spans(), 24);  // the plan itself is in the flat outputs' basis
  flatsos::test::expect_executable(arm.flat, coarse, o.reserves_N);
  // Even the coarsest nested basis that leaves a free coefficient (2 spans, 895 N s) starts it
  // to the same plan. At T = 1 s that basis has no plan along the prescribed path: the flat
  // outputs' own basis starts the path stage instead, and everything is as without the option.
  const fpl::OpenLoopPlan coarsest = plan_with(1);
  ASSERT_EQ(coarsest.status, fpl::SolveStatus::Solved) << coarsest.message;
  EXPECT_EQ(coarsest.free_path.start_flat_output_spans, 2);
  EXPECT_NEAR(coarsest.sos.cost_N_s, fine.sos.cost_N_s, 1e-5 * fine.sos.cost_N_s);
  o.duration_s = 1.0;
  const fpl::OpenLoopPlan fine_1s = plan_with(0), fallback = plan_with(1);
  ASSERT_EQ(fallback.status, fpl::SolveStatus::Solved) << fallback.message;
  EXPECT_EQ(fallback.free_path.start_flat_output_spans, 24);
  EXPECT_EQ(fallback.free_path.prescribed_status, "solved");
  EXPECT_EQ(fallback.free_path.prescribed_cost_N_s, fine_1s.free_path.prescribed_cost_N_s);
  EXPECT_EQ(fallback.sos.cost_N_s, fine_1s.sos.cost_N_s);
  EXPECT_EQ(fallback.free_path.path_iterations, fine_1s.free_path.path_iterations);
}

TEST_F(FreePath, BadOptionsAreNamed) {
  o.free_path.enabled = true;
  auto rejects = [&](fpl::OpenLoopOptions bad, const std::string& field, fpl::OpenLoopStudyOptions bad_study = {}) {
    try {
      fpl::plan_open_loop(arm.flat, s0, bad, bad_study);
      ADD_FAILURE() << "accepted bad " << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  // A bad study setting with the fixture's options.
  auto rejects_study = [&](auto spoil, const std::string& field) {
    fpl::OpenLoopStudyOptions bad_study;
    spoil(bad_study.free_path);
    rejects(o, field, bad_study);
  };
  rejects_study([](auto& f) { f.degree = 4; }, "free_path.degree");
  auto bad = o;
  bad.free_path.spans = 1;
  rejects(bad, "free_path.spans");
  bad = o;
  bad.sos.bounds.enforce = false;
  rejects(bad, "bounds");
  bad = o;
  bad.free_path.span_growth = 0.0;
  rejects(bad, "free_path.span_growth");
  bad.free_path.span_growth = std::nan("");
  rejects(bad, "free_path.span_growth");
  rejects_study([](auto& f) { f.start_min_spans = -1; }, "free_path.start_min_spans");
  rejects_study([](auto& f) { f.relative_tolerance = 0.0; }, "free_path.relative_tolerance");
  rejects_study([](auto& f) { f.exchange_relative_tolerance = -1e-4; }, "free_path.exchange_relative_tolerance");
  rejects_study([](auto& f) { f.exchange_relative_tolerance = std::numeric_limits<double>::infinity(); }, "free_path.exchange_relative_tolerance");
  rejects_study([](auto& f) { f.max_torque_refinements = -1; }, "free_path.max_torque_refinements");
  rejects_study([](auto& f) { f.max_torque_refinements = 11; }, "free_path.max_torque_refinements");
  rejects_study([](auto& f) { f.torque_model_relative_gap = -1e-3; }, "free_path.torque_model_relative_gap");
  rejects_study([](auto& f) { f.torque_model_relative_gap = std::nan(""); }, "free_path.torque_model_relative_gap");
}

// From a minimum-effort rest some muscles start exactly at their reserve, which the initial state
// fixes at t = 0: both path methods must take that row as met (they once asked it for the rows'
// margin too and found no plan along the start path, or Ipopt's restoration failed).
TEST(FreePathFromRest, BothMethodsOptimizeTheElbowsPathWithMusclesStartingAtTheirReserve) {
  const auto model = flatsos::plugin::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) +
                                                                     "/models/elbow_1dof.json");
  const fpl::FlatOutputMap flat(model);
  const Eigen::VectorXd reserves = Eigen::VectorXd::Constant(3, 10.0);
  const SimTK::State rest = fpl::start_state(flat, Eigen::VectorXd::Constant(1, 20.0 * M_PI / 180.0),
                                             Eigen::VectorXd::Zero(1), std::nullopt, reserves);
  const fpl::MuscleState s0 = fpl::muscle_state_of(*model, rest);
  fpl::OpenLoopOptions o;
  o.duration_s = 1.5;
  o.target_q_rad = Eigen::VectorXd::Constant(1, 90.0 * M_PI / 180.0);
  o.reserves_N = reserves;
  const fpl::OpenLoopPlan prescribed = fpl::plan_open_loop(flat, s0, o);
  ASSERT_EQ(prescribed.status, fpl::SolveStatus::Solved) << prescribed.message;
  EXPECT_NEAR(prescribed.check.min_tendon_force_N, 10.0, 1e-6);  // a muscle at its reserve: this test's case
  o.free_path.enabled = true;
  double costs[2] = {0.0, 0.0};
  int k = 0;
  for (const fpl::FreePathMethod method : {fpl::FreePathMethod::ReducedQuasiNewton, fpl::FreePathMethod::JointNewton}) {
    fpl::OpenLoopStudyOptions study;
    study.free_path.method = method;
    const fpl::OpenLoopPlan plan = fpl::plan_open_loop(flat, s0, o, study);
    ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << fpl::to_string(method) << ": " << plan.message;
    EXPECT_TRUE(plan.free_path.optimized);
    EXPECT_LT(plan.sos.cost_N_s, 0.8 * prescribed.sos.cost_N_s);  // measured 53.82 against 73.46 N s
    costs[k++] = plan.sos.cost_N_s;
  }
  EXPECT_NEAR(costs[0], costs[1], 1e-3 * costs[1]);
}
