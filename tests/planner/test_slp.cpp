// The SLP: Ipopt's answer equals a brute-force vertex enumeration, the appendix construction is
// feasible (and never better than the optimum); an RH step on the arm is solved and feasible.
#include <gtest/gtest.h>

#include <iostream>
#include <random>

#include "flatsos/planner/slp_study.hpp"
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
    const auto ipopt = fpl::solve_slp_by_ipopt(CY, B);
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
  EXPECT_NEAR(fpl::solve_slp_by_ipopt(CY, Eigen::VectorXd::Constant(6, -5.0)).cost_N, 0.0, 1e-7);
  EXPECT_NEAR(fpl::solve_slp(CY, Eigen::VectorXd::Constant(6, -5.0)).cost_N, 0.0, 1e-12);
}

TEST(Slp, TheApiDefaultIsTheProgramsExactSolver) {
  EXPECT_EQ(fpl::RecedingHorizonOptions{}.solver, fpl::SlpSolver::VertexEnumeration);
  flatsos::test::ArmPlanning arm;
  const Eigen::VectorXd B = Eigen::VectorXd::LinSpaced(6, -50.0, 200.0);
  const auto by_default = fpl::solve_slp(arm.flat.CY(), B);
  EXPECT_TRUE(by_default.message.empty()) << by_default.message;
  EXPECT_EQ(by_default.iterations, 0);  // no Ipopt iterations: enumerated
  EXPECT_NEAR(by_default.cost_N, fpl::slp_vertex_enumeration(arm.flat.CY(), B).sum(), 1e-12);
}

namespace {
// A random SLP shaped like a posture-dependent step's: `grid` stacked blocks of m rows (C_Y at
// each grid posture, drifting along the horizon), p = m - 1 columns, positive row sums.
struct RandomSlp {
  Eigen::MatrixXd CY;
  Eigen::VectorXd B, cost;
};
RandomSlp random_slp(std::mt19937& rng, int m, int grid) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int p = m - 1;
  Eigen::MatrixXd base(m, p);
  for (auto& c : base.reshaped()) c = u(rng);
  base.rowwise() += Eigen::RowVectorXd::Constant(p, 0.3);  // Assumption 1: row sums > 0
  for (int j = 0; j < m; ++j)
    if (base.row(j).sum() <= 0.1) base.row(j).array() += (0.2 - base.row(j).sum()) / p;
  RandomSlp s;
  s.CY.resize(grid * m, p);
  for (int g = 0; g < grid; ++g) s.CY.middleRows(g * m, m) = base * (1.0 + 0.05 * g) + 0.01 * g * Eigen::MatrixXd::Ones(m, p);
  s.B.resize(grid * m);
  for (auto& b : s.B) b = 200.0 * u(rng);
  s.cost = (0.5 * Eigen::VectorXd::Ones(p) + 0.4 * Eigen::VectorXd::NullaryExpr(p, [&] { return u(rng); }));
  return s;
}
}  // namespace

TEST(Slp, TheDualSimplexMatchesIpoptAndVertexEnumeration) {
  // The arm: every vertex enumerated against the simplex.
  flatsos::test::ArmPlanning arm;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-300.0, 300.0);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::VectorXd B(6);
    for (auto& b : B) b = u(rng);
    const auto simplex = fpl::solve_slp(arm.flat.CY(), B, fpl::SlpSolver::Simplex);
    ASSERT_EQ(simplex.status, fpl::SolveStatus::Solved);
    EXPECT_FALSE(simplex.used_fallback) << simplex.message;
    const double exact = fpl::slp_vertex_enumeration(arm.flat.CY(), B).sum();
    EXPECT_NEAR(simplex.cost_N, exact, 1e-9 * (1 + exact)) << "trial " << trial;
  }
  // Knee- and leg-sized SLPs (13 and 40 muscles, 11 grid postures), with a cost c: Ipopt's
  // interior point is the reference.
  for (const int m : {13, 40}) {
    for (int trial = 0; trial < 5; ++trial) {
      const RandomSlp s = random_slp(rng, m, 11);
      fpl::SlpWorkspace simplex_w, ipopt_w;
      simplex_w.cost = ipopt_w.cost = s.cost;
      fpl::SlpResult simplex, ipopt;
      fpl::solve_slp(s.CY, s.B, fpl::SlpSolver::Simplex, simplex_w, simplex);
      fpl::solve_slp_by_ipopt(s.CY, s.B, std::nullopt, ipopt_w, ipopt);
      ASSERT_EQ(simplex.status, fpl::SolveStatus::Solved);
      ASSERT_FALSE(simplex.used_fallback) << simplex.message;
      ASSERT_FALSE(ipopt.used_fallback) << ipopt.message;
      EXPECT_NEAR(simplex.cost_N, ipopt.cost_N, 1e-7 * (1 + std::abs(ipopt.cost_N))) << m << " muscles, trial " << trial;
      EXPECT_GE((s.CY * simplex.alpha - s.B).minCoeff(), -1e-7 * (1 + s.B.cwiseAbs().maxCoeff()));
      EXPECT_GE(simplex.alpha.minCoeff(), 0.0);
      EXPECT_GT(simplex.iterations, 0);
    }
  }
}

TEST(Slp, TooManyVerticesToEnumerateAreSolvedByTheSimplex) {
  // 24 muscles, 12 flat outputs: C(36, 12) = 1.25e9 vertices.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.1, 1.0);
  Eigen::MatrixXd CY(24, 12);
  for (auto& c : CY.reshaped()) c = u(rng);
  Eigen::VectorXd B(24);
  for (auto& b : B) b = 100.0 * u(rng);
  const auto result = fpl::solve_slp(CY, B, fpl::SlpSolver::VertexEnumeration);
  ASSERT_EQ(result.status, fpl::SolveStatus::Solved);
  EXPECT_TRUE(result.message.empty()) << result.message;
  EXPECT_GT(result.iterations, 0);  // pivots: not enumerated
  EXPECT_NEAR(result.cost_N, fpl::solve_slp_by_ipopt(CY, B).cost_N, 1e-7 * (1 + result.cost_N));
  EXPECT_GE((CY * result.alpha - B).minCoeff(), -1e-6);
}

TEST(Slp, TheSimplexRestartsFromTheLastBasis) {
  // A receding horizon's consecutive SLPs: the same rows, bounds drifting a little. Started from
  // the previous basis, the simplex reaches the same optimum as cold starts in fewer pivots.
  std::mt19937 rng(7);
  RandomSlp s = random_slp(rng, 40, 11);
  std::normal_distribution<double> drift(0.0, 1.0);
  fpl::SlpWorkspace warm_w;
  warm_w.cost = s.cost;
  int warm_pivots = 0, cold_pivots = 0;
  for (int period = 0; period < 20; ++period) {
    for (auto& b : s.B) b += drift(rng);
    fpl::SlpResult warm, cold;
    fpl::solve_slp(s.CY, s.B, fpl::SlpSolver::Simplex, warm_w, warm);
    fpl::SlpWorkspace cold_w;
    cold_w.cost = s.cost;
    fpl::solve_slp(s.CY, s.B, fpl::SlpSolver::Simplex, cold_w, cold);
    ASSERT_FALSE(warm.used_fallback || cold.used_fallback) << warm.message << cold.message;
    EXPECT_NEAR(warm.cost_N, cold.cost_N, 1e-9 * (1 + std::abs(cold.cost_N))) << "period " << period;
    if (period > 0) warm_pivots += warm.iterations, cold_pivots += cold.iterations;
  }
  std::cout << "pivots: warm " << warm_pivots << ", cold " << cold_pivots << "\n";
  EXPECT_LT(warm_pivots, cold_pivots / 2) << "warm " << warm_pivots << " vs cold " << cold_pivots;
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
  o.excitation_bounds.enforce = false;  // the SLP's own optimum (the bounds move it: test_rh_period_bounds)
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

TEST(RecedingHorizonStep, ReturnsTheExcitationsOfItsPlanWithItsTorqueOffset) {
  // Twin: the step's excitations (torque jets shared on a grid) against the pointwise inverse map
  // along its plan, with and without a torque offset, also past the horizon (held at rest).
  flatsos::test::ArmPlanning arm;
  auto ws = arm.model->makeWorkspace();
  fpl::RecedingHorizonOptions o;
  o.target_q_rad = Eigen::Vector2d(flatsos::test::deg(80), flatsos::test::deg(80));
  o.reserves_N = Eigen::VectorXd::Constant(6, 1.0);
  const Eigen::Vector2d q(flatsos::test::deg(20), flatsos::test::deg(20)), qd(0.3, -0.2);
  for (const Eigen::VectorXd& offset : {Eigen::VectorXd(), Eigen::VectorXd(Eigen::Vector2d(1.5, -2.0))}) {
    o.torque_offset_N_m = offset;
    const auto step = fpl::plan_receding_horizon_step(arm.flat, ws, q, qd, o);
    ASSERT_EQ(step.status, fpl::SolveStatus::Solved) << step.message;
    fpl::Jet Y = fpl::Jet::Zero(4, 3);
    Y.col(0) = step.alpha();
    // Inside the horizon, and past its end (held at rest). Near the end itself the cubic's
    // acceleration jumps to the rest's zero, so the torque rates there are not defined.
    for (const auto& [tau0, h] : {std::pair{0.0, 0.04}, std::pair{0.6, 0.05}}) {
      const Eigen::MatrixXd n = step.excitations(arm.flat, ws, tau0, h, 11);
      ASSERT_EQ(n.rows(), 11);
      ASSERT_EQ(n.cols(), 6);
      for (int i = 0; i < 11; ++i) {
        const double tau = tau0 + h * i;
        fpl::Jet qj = step.path.jet(std::min(tau, 0.5), 5);
        if (tau >= 0.5) qj.rightCols(4).setZero();
        fpl::TorqueJet tj = arm.flat.torqueJet(ws, qj);
        if (offset.size()) tj.tau.col(0) -= offset;
        const auto expected = arm.flat.inverseFromTorque(qj, tj, Y);
        EXPECT_LT((n.row(i).transpose() - expected.excitation).cwiseAbs().maxCoeff(), 1e-7) << "tau " << tau;
      }
    }
  }
  fpl::RecedingHorizonStep unsolved;
  EXPECT_THROW(unsolved.excitations(arm.flat, ws, 0.0, 0.01, 3), std::logic_error);
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
