// The SLP: Ipopt's answer equals a brute-force vertex enumeration, the appendix construction is
// feasible (and never better than the optimum); an RH step on the arm is solved and feasible.
#include <gtest/gtest.h>

#include <random>

#include "scenario_fixture.hpp"

namespace fpl = flatsos::planner;
namespace fp = flatsos::plugin;

TEST(Slp, IpoptMatchesVertexEnumerationAndAppendixIsFeasible) {
  flatsos::test::ArmPlanning arm;
  const Eigen::MatrixXd& CY = arm.flat.CY();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-300.0, 300.0);
  for (int trial = 0; trial < 30; ++trial) {
    Eigen::VectorXd B(6);
    for (auto& b : B) b = u(rng);
    const Eigen::VectorXd exact = fpl::slp_vertex_enumeration(CY, B);
    const auto ipopt = fpl::solve_slp(CY, B);
    ASSERT_EQ(ipopt.status, fpl::SolveStatus::Solved);
    EXPECT_FALSE(ipopt.used_fallback) << ipopt.message;
    EXPECT_NEAR(ipopt.cost_N, exact.sum(), 1e-6 * (1 + exact.sum())) << "trial " << trial;
    EXPECT_GE((CY * ipopt.alpha - B).minCoeff(), -1e-6);
    EXPECT_GE(ipopt.alpha.minCoeff(), 0.0);
    const Eigen::VectorXd appendix = fpl::slp_appendix_solution(CY, B);
    EXPECT_GE((CY * appendix - B).minCoeff(), -1e-9 * (1 + B.cwiseAbs().maxCoeff()));
    EXPECT_GE(appendix.minCoeff(), 0.0);
    EXPECT_GE(appendix.sum(), exact.sum() - 1e-9);
    const auto enumerated = fpl::solve_slp(CY, B, fpl::SlpSolver::VertexEnumeration);
    EXPECT_NEAR(enumerated.cost_N, exact.sum(), 1e-12 * (1 + exact.sum()));
  }
  // All bounds below zero: nothing to pull, alpha = 0.
  EXPECT_NEAR(fpl::solve_slp(CY, Eigen::VectorXd::Constant(6, -5.0)).cost_N, 0.0, 1e-7);
}

TEST(Slp, RejectsBadInput) {
  EXPECT_THROW(fpl::solve_slp(Eigen::MatrixXd::Ones(3, 2), Eigen::VectorXd::Ones(2)), std::invalid_argument);
  Eigen::MatrixXd bad = Eigen::MatrixXd::Ones(3, 2);
  bad(1, 0) = -2.0;  // row sum -1: Assumption 1 condition 3
  EXPECT_THROW(fpl::solve_slp(bad, Eigen::VectorXd::Ones(3)), std::invalid_argument);
  EXPECT_THROW(fpl::solve_slp(Eigen::MatrixXd::Ones(3, 2), Eigen::Vector3d(1, std::nan(""), 0)), std::invalid_argument);
}

TEST(RecedingHorizonStep, SolvesTheFirstStepOfThePaperScenario) {
  flatsos::test::ArmPlanning arm;
  fpl::RecedingHorizonOptions o;
  o.target_q_rad = Eigen::Vector2d(flatsos::test::deg(80), flatsos::test::deg(80));
  o.reserves_N = Eigen::VectorXd::Constant(6, 1.0);
  const Eigen::Vector2d q(flatsos::test::deg(20), flatsos::test::deg(20));
  const auto step = fpl::plan_receding_horizon_step(arm.flat, q, Eigen::Vector2d::Zero(), o);
  ASSERT_EQ(step.status, fpl::SolveStatus::Solved) << step.message;
  EXPECT_NEAR(step.path.jet(0.5, 2)(0, 0), flatsos::test::deg(80), 1e-12);
  const Eigen::VectorXd B = fpl::slp_bound_vector(arm.flat.Ctau(), step.tau_min, step.tau_max, o.reserves_N);
  EXPECT_GE((arm.flat.CY() * step.alpha() - B).minCoeff(), -1e-6);
  EXPECT_NEAR(step.slp.cost_N, fpl::slp_vertex_enumeration(arm.flat.CY(), B).sum(), 1e-6 * step.slp.cost_N);
  // Every tendon force of the plan stays >= the reserve on the horizon grid: F = C_tau tau + C_Y alpha.
  for (int i = 0; i <= 10; ++i) {
    const auto j = step.path.jet(0.05 * i, 3);
    const Eigen::VectorXd F = arm.flat.Ctau() * arm.flat.torque(j.col(0), j.col(1), j.col(2)) + arm.flat.CY() * step.alpha();
    EXPECT_GE(F.minCoeff(), 1.0 - 1e-6);
  }
  EXPECT_THROW(fpl::plan_receding_horizon_step(arm.flat, q, Eigen::Vector2d::Zero(), [&] { auto b = o; b.horizon_s = -1; return b; }()),
               std::invalid_argument);
}

TEST(RecedingHorizonStep, TheClosedFormCubicIsTheHermiteFit) {
  // Twin: fit_rest_cubic's closed form against the general Hermite solve of fit_joint_path.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  fpl::JointPath reused;
  for (int trial = 0; trial < 20; ++trial) {
    const double T = 0.1 + std::abs(u(rng));
    const Eigen::Vector3d q(u(rng), u(rng), u(rng)), qd(u(rng), u(rng), u(rng)), target(u(rng), u(rng), u(rng));
    Eigen::MatrixXd initial(3, 2), terminal = Eigen::MatrixXd::Zero(3, 2);
    initial << q, qd;
    terminal.col(0) = target;
    const fpl::JointPath hermite = fpl::fit_joint_path(T, initial, terminal);
    fpl::fit_rest_cubic(T, q, qd, target, reused);  // the same object every trial
    ASSERT_EQ(reused.q.size(), 3u);
    EXPECT_EQ(reused.duration_s, T);
    for (int i = 0; i < 3; ++i)
      EXPECT_LT((reused.q[static_cast<std::size_t>(i)].coefficients() - hermite.q[static_cast<std::size_t>(i)].coefficients())
                    .cwiseAbs()
                    .maxCoeff(),
                1e-9 * (1.0 + hermite.q[static_cast<std::size_t>(i)].coefficients().cwiseAbs().maxCoeff()));
  }
  EXPECT_THROW(fpl::fit_rest_cubic(0.0, Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), reused),
               std::invalid_argument);
  EXPECT_THROW(fpl::fit_rest_cubic(1.0, Eigen::Vector2d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector2d::Zero(), reused),
               std::invalid_argument);
}

TEST(RecedingHorizonStep, AReusedStepGivesWhatAFreshOneGives) {
  // The in-place planner reuses the step's storage: a step that planned from another state
  // before must give exactly the fresh result (nothing stale carried over).
  flatsos::test::ArmPlanning arm;
  fpl::RecedingHorizonOptions o;
  o.target_q_rad = Eigen::Vector2d(flatsos::test::deg(80), flatsos::test::deg(80));
  o.reserves_N = Eigen::VectorXd::Constant(6, 1.0);
  o.solver = fpl::SlpSolver::VertexEnumeration;
  fp::ModelWorkspace ws = arm.flat.makeWorkspace();
  fpl::RecedingHorizonStep reused;
  fpl::plan_receding_horizon_step(arm.flat, ws, Eigen::Vector2d(0.1, 1.2), Eigen::Vector2d(2.0, -1.0), o, reused);
  const Eigen::Vector2d q(flatsos::test::deg(20), flatsos::test::deg(30)), qd(0.3, -0.2);
  fpl::plan_receding_horizon_step(arm.flat, ws, q, qd, o, reused);
  const auto fresh = fpl::plan_receding_horizon_step(arm.flat, q, qd, o);
  ASSERT_EQ(fresh.status, fpl::SolveStatus::Solved);
  EXPECT_EQ(reused.status, fresh.status);
  EXPECT_EQ(reused.alpha(), fresh.alpha());
  EXPECT_EQ(reused.tau_min, fresh.tau_min);
  EXPECT_EQ(reused.tau_max, fresh.tau_max);
  EXPECT_EQ(reused.bound_N, fresh.bound_N);
  for (std::size_t i = 0; i < 2; ++i) EXPECT_EQ(reused.path.q[i].coefficients(), fresh.path.q[i].coefficients());
}
