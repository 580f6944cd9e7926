// A receding-horizon step that minimizes a nonlinear effort (receding_horizon/step_effort.hpp):
// its effort recomputed independently from the excitations the step asks for (the sampled inverse
// map), first-order optimality with finite-difference gradients of that recomputation and of the
// sampled bounds (not the sequential QP's analytic ones), cheaper than the linear effort's plan
// by the same measure, and bad effort options named.
#include <gtest/gtest.h>

#include <Eigen/QR>

#include "flatsos/planner/receding_horizon_step.hpp"
#include "first_period_constraints.hpp"
#include "scenario_fixture.hpp"

namespace fpl = flatsos::planner;
namespace fp = flatsos::plugin;
using flatsos::test::deg;

namespace {

struct PaperStep {
  flatsos::test::ArmPlanning arm;
  fp::ModelWorkspace ws = arm.flat.makeWorkspace();
  fpl::RecedingHorizonOptions options = [] {
    fpl::RecedingHorizonOptions o;
    o.target_q_rad = Eigen::Vector2d(deg(60), deg(60));
    o.reserves_N = Eigen::VectorXd::Constant(6, 1.0);
    return o;
  }();
  Eigen::Vector2d q{deg(30), deg(40)}, qd{0.2, 0.1};

  fpl::RecedingHorizonStep plan(std::shared_ptr<const fpl::Effort> effort) {
    fpl::RecedingHorizonOptions o = options;
    o.effort = std::move(effort);
    return fpl::plan_receding_horizon_step(arm.flat, ws, q, qd, o);
  }
  // The integral of sum n^2 over the horizon as the step defines it (grid_points times i T /
  // grid_points, each weighing T / grid_points), from the excitations the plan asks for.
  double excitation_squared(const fpl::RecedingHorizonStep& step, const Eigen::VectorXd& alpha) {
    const double h = options.horizon_s / options.grid_points;
    fpl::PlanExcitationScratch scratch;
    Eigen::MatrixXd n;
    EXPECT_TRUE(fpl::sample_plan_excitations(arm.flat, ws, step.path, alpha, step.torque_offset_N_m, 0.0, h,
                                             options.grid_points, scratch, n));
    return h * n.squaredNorm();
  }
  // Every constraint as c(alpha) >= 0 (first_period_constraints.hpp).
  Eigen::VectorXd constraints(const fpl::RecedingHorizonStep& step, const Eigen::VectorXd& alpha) {
    return flatsos::test::first_period_constraints(arm.flat, ws, options.excitation_bounds, step, alpha);
  }
};

}  // namespace

TEST(RecedingHorizonStepEffort, SquaredExcitationsAtAFirstOrderOptimumBelowTheLinearPlan) {
  PaperStep s;
  const auto linear = s.plan(nullptr);
  const auto squared = s.plan(fpl::effort_named("excitation_squared"));
  ASSERT_EQ(linear.status, fpl::SolveStatus::Solved) << linear.message;
  ASSERT_EQ(squared.status, fpl::SolveStatus::Solved) << squared.message;
  EXPECT_GT(squared.effort_iterations, 0);
  EXPECT_EQ(linear.effort_iterations, 0);
  ASSERT_TRUE(squared.first_period_sampled);
  const Eigen::VectorXd alpha = squared.alpha();
  const double effort = s.excitation_squared(squared, alpha);
  EXPECT_NEAR(squared.effort_value, effort, 1e-9 * effort);
  const double linear_effort = s.excitation_squared(linear, linear.alpha());
  std::cout << "[ measure  ] integral of sum n^2 over the horizon: " << effort << " (the linear effort's plan "
            << linear_effort << "), " << squared.effort_iterations << " sequential QP steps\n";
  EXPECT_LT(effort, 0.9 * linear_effort);

  const Eigen::VectorXd c = s.constraints(squared, alpha);
  EXPECT_GE(c.head(c.size() - 12).minCoeff(), 0.0);          // n and a inside, exactly
  EXPECT_GE(c.segment(c.size() - 12, 6).minCoeff(), -1e-6);  // reserves (N)
  EXPECT_GE(alpha.minCoeff(), 0.0);
  // First order: the effort's gradient is a nonnegative combination of the active constraints'
  // gradients, all by central differences of the sampled inverse map.
  const int p = static_cast<int>(alpha.size());
  std::vector<int> active;
  for (Eigen::Index k = 0; k < c.size(); ++k)
    if (c[k] < 1e-3) active.push_back(static_cast<int>(k));
  ASSERT_LE(static_cast<int>(active.size()), p) << "degenerate: more active constraints than flat outputs";
  Eigen::VectorXd gradient(p);
  Eigen::MatrixXd J(p, static_cast<Eigen::Index>(active.size()));
  const double h = 1e-3;  // N, of flat outputs of tens to hundreds of N
  for (int l = 0; l < p; ++l) {
    Eigen::VectorXd up = alpha, down = alpha;
    up[l] += h;
    down[l] -= h;
    gradient[l] = (s.excitation_squared(squared, up) - s.excitation_squared(squared, down)) / (2 * h);
    const Eigen::VectorXd dc = (s.constraints(squared, up) - s.constraints(squared, down)) / (2 * h);
    for (std::size_t k = 0; k < active.size(); ++k) J(l, static_cast<Eigen::Index>(k)) = dc[active[k]];
  }
  Eigen::VectorXd mu = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(active.size()));
  if (!active.empty()) mu = J.colPivHouseholderQr().solve(gradient);
  EXPECT_LT((J * mu - gradient).norm(), 1e-4 * gradient.norm())
      << "not stationary: gradient " << gradient.transpose() << ", multipliers " << mu.transpose();
  if (!active.empty()) {
    EXPECT_GE(mu.minCoeff(), -1e-6 * gradient.norm()) << "the effort still falls along an active constraint";
  }
}

TEST(RecedingHorizonStepEffort, BadEffortsAreNamed) {
  PaperStep s;
  try {
    s.plan(fpl::effort_named("tendon_force", Eigen::VectorXd::Ones(6)));
    ADD_FAILURE() << "a linear effort in the options was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("withEffort"), std::string::npos) << e.what();
  }
  EXPECT_THROW(s.plan(fpl::effort_named("excitation_squared", Eigen::VectorXd::Ones(5))), std::invalid_argument);
}
