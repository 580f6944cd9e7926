// The effort summed over time points (bounds/effort_model.hpp), checked by finite-difference
// twins: its gradient against central differences of its value for each effort of the field,
// and for the stress effort (F / Fmax)^2, where F is affine in theta and the Gauss-Newton Hessian
// is the exact one, its Hessian against differences of the gradient. The points use a subset of
// theta's entries, in another order, as the open-loop plan's B-spline points do.
#include <gtest/gtest.h>

#include <random>
#include <string>

#include <Eigen/Eigenvalues>

#include "../plugin/arm_fixture.hpp"
#include "bounds/effort_model.hpp"
#include "flatsos/planner/effort.hpp"
#include "flatsos/planner/flat_outputs.hpp"

namespace fpl = flatsos::planner;
namespace fd = flatsos::planner::detail;

namespace {

// Three points on the paper's arm, each moved by 4 of theta's 7 entries.
std::vector<fd::BoundPoint> arm_points(const fpl::FlatOutputMap& flat) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const int m = flat.numMuscles();
  std::vector<fd::BoundPoint> points;
  for (int i = 0; i < 3; ++i) {
    fd::BoundPoint bp;
    bp.t_s = 0.1 * i;
    const Eigen::VectorXd q = Eigen::Vector2d(flatsos::test::deg(20.0 * i), flatsos::test::deg(30.0 + 10.0 * i));
    const Eigen::VectorXd L = flat.model().musculotendonLengths(q);
    bp.base.resize(m, 3);
    for (int j = 0; j < m; ++j) {
      bp.base.row(j) << 120.0 + 40.0 * unit(rng), 60.0 * unit(rng), 300.0 * unit(rng);
      bp.path.push_back({L[j], 0.05 * unit(rng), 0.2 * unit(rng)});
    }
    bp.columns = {6 - i, 1, 3 + (i == 0), 0};
    for (auto& s : bp.slope) s = Eigen::MatrixXd::NullaryExpr(m, 4, [&] { return 0.5 * unit(rng); });
    points.push_back(std::move(bp));
  }
  return points;
}

}  // namespace

TEST(EffortModel, GradientsMatchCentralDifferencesForEveryEffort) {
  const fpl::FlatOutputMap flat(flatsos::test::load_arm());
  const std::vector<fd::BoundPoint> points = arm_points(flat);
  const std::vector<double> weights_s{0.02, 0.05, 0.03};
  const Eigen::VectorXd theta = Eigen::VectorXd::LinSpaced(7, -2.0, 3.0);
  for (const std::string& name : fpl::effort_names()) {
    if (name == "tendon_force") continue;  // needs weights; linear
    const auto effort = fpl::effort_named(name);
    fd::EffortModel at, plus, minus;
    ASSERT_TRUE(fd::evaluate_effort(flat, *effort, points, weights_s, theta, true, at)) << name;
    ASSERT_GT(at.value, 0.0) << name;
    for (int c = 0; c < 7; ++c) {
      const double h = 1e-5;
      Eigen::VectorXd tp = theta, tm = theta;
      tp[c] += h, tm[c] -= h;
      ASSERT_TRUE(fd::evaluate_effort(flat, *effort, points, weights_s, tp, false, plus));
      ASSERT_TRUE(fd::evaluate_effort(flat, *effort, points, weights_s, tm, false, minus));
      const double numeric = (plus.value - minus.value) / (2.0 * h);
      EXPECT_NEAR(at.gradient[c], numeric, 1e-6 * (std::abs(numeric) + at.value)) << name << " entry " << c;
    }
    // Entry 2 moves no point: no gradient, no Hessian.
    EXPECT_EQ(at.gradient[2], 0.0) << name;
    EXPECT_EQ(at.hessian.row(2).cwiseAbs().sum(), 0.0) << name;
    EXPECT_LT((at.hessian - at.hessian.transpose()).cwiseAbs().maxCoeff(), 1e-12 * at.hessian.cwiseAbs().maxCoeff());
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(at.hessian).eigenvalues().minCoeff(),
              -1e-12 * at.hessian.cwiseAbs().maxCoeff()) << name << ": a Gauss-Newton Hessian of a convex term";
  }
}

TEST(EffortModel, TheStressEffortsHessianIsExact) {
  const fpl::FlatOutputMap flat(flatsos::test::load_arm());
  const std::vector<fd::BoundPoint> points = arm_points(flat);
  const std::vector<double> weights_s{0.02, 0.05, 0.03};
  const Eigen::VectorXd theta = Eigen::VectorXd::LinSpaced(7, -2.0, 3.0);
  const auto effort = fpl::effort_named("stress_squared");
  fd::EffortModel at, plus, minus;
  ASSERT_TRUE(fd::evaluate_effort(flat, *effort, points, weights_s, theta, true, at));
  for (int c = 0; c < 7; ++c) {
    const double h = 1e-3;  // the gradient is affine in theta: differences are exact to rounding
    Eigen::VectorXd tp = theta, tm = theta;
    tp[c] += h, tm[c] -= h;
    ASSERT_TRUE(fd::evaluate_effort(flat, *effort, points, weights_s, tp, true, plus));
    ASSERT_TRUE(fd::evaluate_effort(flat, *effort, points, weights_s, tm, true, minus));
    const Eigen::VectorXd numeric = (plus.gradient - minus.gradient) / (2.0 * h);
    EXPECT_LT((at.hessian.col(c) - numeric).cwiseAbs().maxCoeff(), 1e-9 * at.hessian.cwiseAbs().maxCoeff()) << c;
  }
}

TEST(EffortModel, AnUnreachableExcitationFailsUnlessTheClosestIsAskedAndItsGradientFollowsItsValues) {
  const fpl::FlatOutputMap flat(flatsos::test::load_arm());
  std::vector<fd::BoundPoint> points = arm_points(flat);
  points[1].base(2, 1) = -1e5;  // the force falls faster than any deactivation allows
  const std::vector<double> weights_s{0.02, 0.05, 0.03};
  const Eigen::VectorXd theta = Eigen::VectorXd::Zero(7);
  const auto effort = fpl::effort_named("excitation_squared");
  fd::EffortModel out;
  EXPECT_FALSE(fd::evaluate_effort(flat, *effort, points, weights_s, theta, true, out));
  ASSERT_TRUE(fd::evaluate_effort(flat, *effort, points, weights_s, theta, true, out, true));
  EXPECT_TRUE(std::isfinite(out.value));
  // The closest excitation's gradient is consistent with its values (a sequential QP relies on
  // it): central differences of the effort agree.
  for (int c = 0; c < 7; ++c) {
    const double h = 1e-4;
    Eigen::VectorXd tp = theta, tm = theta;
    tp[c] += h, tm[c] -= h;
    fd::EffortModel plus, minus;
    ASSERT_TRUE(fd::evaluate_effort(flat, *effort, points, weights_s, tp, false, plus, true));
    ASSERT_TRUE(fd::evaluate_effort(flat, *effort, points, weights_s, tm, false, minus, true));
    const double numeric = (plus.value - minus.value) / (2.0 * h);
    EXPECT_NEAR(out.gradient[c], numeric, 1e-5 * (std::abs(numeric) + out.value)) << "entry " << c;
  }
}
