// The SOS program on the paper's open-loop scenario (the paper, section 5): solved by default with every
// tendon force at or above its reserve on a 10x denser grid; its optimum checked against an
// independent lower bound (an LP written in dense_grid_bound.hpp, with the exact torques at a dense grid); the
// paper's single torque box reported infeasible with the reason; bad input rejected by name.
#include <gtest/gtest.h>

#include "dense_grid_bound.hpp"
#include "flatsos/planner/open_loop_study.hpp"
#include "flatsos/planner/rest_state.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "scenario_fixture.hpp"

namespace fpl = flatsos::planner;

class OpenLoopScenario : public ::testing::Test {
 protected:
  flatsos::test::ArmPlanning arm;
  fpl::MuscleState s0 = flatsos::test::open_loop_initial_state(*arm.model);
  fpl::OpenLoopOptions options = flatsos::test::open_loop_options();
};

TEST_F(OpenLoopScenario, DefaultFormulationSolvesWithEveryReserveMetOnATenfoldGrid) {
  const auto plan = fpl::plan_open_loop(arm.flat, s0, options);
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
  EXPECT_TRUE(plan.message.empty()) << plan.message;
  EXPECT_EQ(plan.check.points, 301);  // 10x the paper's 31-point grid
  EXPECT_GE(plan.check.min_reserve_margin_N, 0.0);
  EXPECT_GE(plan.sos.min_constraint_value_N, 0.0);
  EXPECT_EQ(plan.check.points_outside_domain, 0) << plan.check.first_violation;
  EXPECT_GT(plan.check.min_activation, 0.0);
  EXPECT_LE(plan.check.max_activation, 1.0);
  EXPECT_GE(plan.check.min_excitation, 0.0);
  EXPECT_LE(plan.check.max_excitation, 1.0);
  EXPECT_TRUE(plan.sos.certified) << plan.sos.certified_pieces << " of " << plan.sos.near_active_pieces;
  EXPECT_GT(plan.sos.near_active_pieces, 0);
  // The joint path reaches the target at rest.
  const fpl::Jet end = plan.jointJet(3.0);
  EXPECT_NEAR(end(0, 0), flatsos::test::deg(90), 1e-10);
  EXPECT_NEAR(end.col(1).norm() + end.col(2).norm(), 0.0, 1e-9);
}

TEST_F(OpenLoopScenario, OptimumIsWithinOnePercentAboveAnIndependentDenseGridBound) {
  const auto plan = fpl::plan_open_loop(arm.flat, s0, options);
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
  const double bound = flatsos::test::dense_grid_lower_bound(arm.flat, plan, s0, Eigen::VectorXd::Constant(6, 10.0), 601);
  EXPECT_GE(plan.sos.cost_N_s, bound - 1e-6 * bound);
  EXPECT_LE(plan.sos.cost_N_s, 1.01 * bound);
  // The conservativeness vanishes as the torque model refines: more pieces -> closer.
  auto finer = options;
  finer.torque.pieces = 30;
  const auto fine = fpl::plan_open_loop(arm.flat, s0, finer);
  ASSERT_EQ(fine.status, fpl::SolveStatus::Solved) << fine.message;
  EXPECT_LE(fine.sos.cost_N_s, plan.sos.cost_N_s + 1e-6);
  EXPECT_LE(fine.sos.cost_N_s, 1.001 * bound);
  EXPECT_GE(fine.sos.cost_N_s, bound - 1e-6 * bound);
}

TEST_F(OpenLoopScenario, PapersSingleTorqueBoxIsReportedInfeasibleWithTheReason) {
  options.torque.pieces = 1;
  fpl::OpenLoopStudyOptions box;
  box.torque.degree = 0;
  box.torque.samples_per_piece = 31;
  const auto plan = fpl::plan_open_loop(arm.flat, s0, options, box);
  EXPECT_EQ(plan.status, fpl::SolveStatus::Infeasible);
  EXPECT_NE(plan.message.find("t = 0 s"), std::string::npos) << plan.message;
  EXPECT_NE(plan.message.find("reserve of 10 N"), std::string::npos) << plan.message;
  EXPECT_NE(plan.message.find("remainder"), std::string::npos) << plan.message;
  EXPECT_FALSE(plan.Y);  // nothing usable comes back with a failure
}

TEST_F(OpenLoopScenario, AnInitialTendonForceBelowItsReserveIsNamedAsTheCause) {
  // The reserve of one muscle just above its tendon force in the initial state: infeasible at
  // t = 0 whatever the formulation, and the message says so (not "more pieces or a higher degree").
  const int j = 3;
  const auto& mp = arm.model->muscle(j).getParameters();
  const double F0 = flatsos::muscles::tendon_force(mp, s0.tendon_length_m[j]);
  options.reserves_N[j] = F0 + 0.5;
  const auto plan = fpl::plan_open_loop(arm.flat, s0, options);
  EXPECT_EQ(plan.status, fpl::SolveStatus::Infeasible);
  EXPECT_NE(plan.message.find("initial tendon force of '" + mp.name + "'"), std::string::npos) << plan.message;
  EXPECT_NE(plan.message.find("below its reserve"), std::string::npos) << plan.message;
  EXPECT_FALSE(plan.Y);
  // Just below the force it is not the cause: the plan is solved.
  options.reserves_N[j] = std::min(F0 - 0.5, 10.0);
  EXPECT_EQ(fpl::plan_open_loop(arm.flat, s0, options).status, fpl::SolveStatus::Solved);
}

TEST_F(OpenLoopScenario, BadInputIsRejectedByName) {
  auto expect_message = [&](fpl::OpenLoopOptions o, fpl::MuscleState s, const std::string& text) {
    try {
      fpl::plan_open_loop(arm.flat, s, o);
      ADD_FAILURE() << "accepted; expected: " << text;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  auto o = options;
  o.duration_s = 0.0;
  expect_message(o, s0, "duration T must be > 0");
  o = options;
  o.reserves_N = Eigen::VectorXd::Constant(5, 10.0);
  expect_message(o, s0, "reserves: expected 6 values");
  o.reserves_N = Eigen::VectorXd::Constant(6, -1.0);
  expect_message(o, s0, "reserves must be >= 0");
  o = options;
  o.target_q_rad = Eigen::Vector3d(1, 2, 3);
  expect_message(o, s0, "target joint angles: expected 2 values");
  o.target_q_rad = Eigen::Vector2d(std::nan(""), 0.0);
  expect_message(o, s0, "target joint angles: values must be finite");
  o = options;
  o.sos.flat_output_degree = 2;
  expect_message(o, s0, "degree 2 with 1 span(s) is too low for 4 boundary equalities");
  o.sos.flat_output_degree = 3;
  o.sos.flat_output_spans = -1;  // 0 asks for the automatic choice
  expect_message(o, s0, "flat outputs need at least 1 span");
  auto s = s0;
  s.activation[2] = 0.0;
  expect_message(options, s, "activation of 'biceps' is 0");
  s = s0;
  s.tendon_length_m[5] = 0.017;
  expect_message(options, s, "tendon of 'brachialis' is slack");
  s = s0;
  s.qd_rad_per_s = Eigen::Vector2d(std::nan(""), 0.0);
  expect_message(options, s, "qd must have 2 finite values");
}

TEST_F(OpenLoopScenario, SimplexExchangeReachesIpoptsOptimum) {
  const auto fast = fpl::plan_open_loop(arm.flat, s0, options);
  fpl::OpenLoopStudyOptions ipopt_only;
  ipopt_only.sos.exchange.lp_solver = fpl::ExchangeLpSolver::Ipopt;
  const auto slow = fpl::plan_open_loop(arm.flat, s0, options, ipopt_only);
  ASSERT_EQ(fast.status, fpl::SolveStatus::Solved) << fast.message;
  ASSERT_EQ(slow.status, fpl::SolveStatus::Solved) << slow.message;
  EXPECT_NEAR(fast.sos.cost_N_s, slow.sos.cost_N_s, 1e-6 * slow.sos.cost_N_s);
  EXPECT_GT(fast.sos.simplex_pivots, 0);
  EXPECT_EQ(slow.sos.simplex_pivots, 0);
  EXPECT_LT(fast.sos.ipopt_calls, slow.sos.ipopt_calls);  // only the certificates
  ASSERT_TRUE(fast.Y && slow.Y);
  for (int l = 0; l < fast.Y->signals(); ++l)
    for (double t : {0.0, 1.0, 2.0, 3.0})
      EXPECT_NEAR(fast.Y->derivativeAt(l, t), slow.Y->derivativeAt(l, t), 1e-4 * (1 + std::abs(slow.Y->derivativeAt(l, t))));
}

TEST_F(OpenLoopScenario, SosProgramRejectsBoundaryConditionsOfTheWrongSizeAndBadHorizons) {
  const auto plan = fpl::plan_open_loop(arm.flat, s0, options);
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved);
  const Eigen::VectorXd reserves = Eigen::VectorXd::Constant(6, 10.0);
  auto expect_message = [&](const fpl::FlatOutputBoundary& bc, double T, const std::string& text) {
    try {
      fpl::solve_sos_program(arm.flat, plan.torque, T, bc, reserves);
      ADD_FAILURE() << "accepted; expected: " << text;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  fpl::FlatOutputBoundary bc;
  bc.initial = Eigen::MatrixXd::Zero(3, 2);  // 3 rows for 4 flat outputs
  bc.terminal = Eigen::MatrixXd::Zero(4, 2);
  expect_message(bc, 3.0, "one row per flat output (4)");
  bc.initial = Eigen::MatrixXd::Zero(4, 2);
  bc.terminal(1, 1) = std::nan("");
  expect_message(bc, 3.0, "must be finite");
  bc.terminal = Eigen::MatrixXd::Zero(4, 2);
  expect_message(bc, 0.0, "horizon T must be > 0");
  expect_message(bc, -1.0, "horizon T must be > 0");
}

TEST(OpenLoopFromRest, TheLibrarysOwnMinimumEffortRestStateIsAFeasibleStartWithTheSameReserves) {
  // The rest state meets some reserves exactly (the SLP's active constraints); the plan from it
  // with the same reserves must still be feasible, on the arm, on a 1-joint elbow and on the
  // elbow with posture-dependent paths (from 0 deg with 1 N its plan needs the excitation bounds).
  for (const char* file : {"arm_richter_warner.json", "elbow_1dof.json", "elbow_posture_dependent.json"}) {
    const auto model = flatsos::plugin::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) + "/models/" + file);
    const fpl::FlatOutputMap flat(model);
    const int n = model->numJoints(), m = model->numMuscles();
    for (double reserve : {1.0, 10.0, 30.0}) {
      for (double q0_deg : {0.0, 20.0, 60.0}) {
        SimTK::State s = model->defaultState();
        const Eigen::VectorXd reserves = Eigen::VectorXd::Constant(m, reserve);
        fpl::set_minimum_effort_rest_state(flat, s, Eigen::VectorXd::Constant(n, flatsos::test::deg(q0_deg)), reserves);
        fpl::OpenLoopOptions o = fpl::open_loop_options(fpl::Preset::Paper);
        o.duration_s = 2.0;
        o.target_q_rad = Eigen::VectorXd::Constant(n, flatsos::test::deg(q0_deg + 30.0));
        o.reserves_N = reserves;
        const auto plan = fpl::plan_open_loop(flat, fpl::muscle_state_of(*model, s), o);
        EXPECT_EQ(plan.status, fpl::SolveStatus::Solved) << file << ", reserve " << reserve << " N, q0 " << q0_deg << " deg: " << plan.message;
        EXPECT_TRUE(plan.sos.certified) << file << ", reserve " << reserve << " N, q0 " << q0_deg << " deg";
        EXPECT_GE(plan.check.min_reserve_margin_N, -1e-6);
      }
    }
  }
}

TEST_F(OpenLoopScenario, ATargetInDegreesGivenAsRadiansIsRejectedWhereNoTendonCanBeTaut) {
  options.target_q_rad = Eigen::Vector2d(90.0, 0.0);  // "90" meant as degrees
  try {
    fpl::plan_open_loop(arm.flat, s0, options);
    ADD_FAILURE() << "a target of 90 rad was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("target joint angles: the musculotendon path of 'anterior_deltoid' would be -4.316 m long"),
              std::string::npos)
        << e.what();
  }
}

TEST(OpenLoopWarnings, ATargetBeyondOneTurnThatIsPossibleIsPlannedWithAWarning) {
  // Moment arms a tenth of the arm's: 7 rad at the shoulder keeps every tendon taut.
  auto d = flatsos::plugin::load_model_file(flatsos::test::arm_model_path());
  for (auto& muscle : d.muscles) muscle.moment_arms_m *= 0.1;
  const auto model = std::make_shared<const flatsos::plugin::MusculoskeletalModel>(d);
  const fpl::FlatOutputMap flat(model);
  auto o = flatsos::test::open_loop_options();
  o.target_q_rad = Eigen::Vector2d(7.0, 0.0);
  const auto plan = fpl::plan_open_loop(flat, flatsos::test::open_loop_initial_state(*model), o);
  ASSERT_EQ(plan.warnings.size(), 1u);
  EXPECT_EQ(plan.warnings[0], "target joint angles.shoulder: 7 rad is beyond one turn (degrees given as radians?)");
  o.target_q_rad = Eigen::Vector2d(1.0, 0.0);
  EXPECT_TRUE(fpl::plan_open_loop(flat, flatsos::test::open_loop_initial_state(*model), o).warnings.empty());
}

TEST_F(OpenLoopScenario, ThePapersArmWithOrderOnePolynomialPathsGivesTheSamePlan) {
  // Every muscle's constant moment arms rewritten as OpenSim's order-1 polynomial of
  // (shoulder, elbow), coefficients 1, elbow, shoulder.
  auto description = flatsos::plugin::load_model_file(flatsos::test::arm_model_path());
  for (auto& m : description.muscles) {
    m.polynomial_path = flatsos::plugin::PolynomialPathDescription{
        {"shoulder", "elbow"}, 1, {m.length_at_zero_angles_m, -m.moment_arms_m[1], -m.moment_arms_m[0]}, {}};
    m.length_at_zero_angles_m = 0.0;
    m.moment_arms_m.resize(0);
  }
  const auto model = std::make_shared<const flatsos::plugin::MusculoskeletalModel>(description);
  const fpl::FlatOutputMap flat(model);
  const auto plan = fpl::plan_open_loop(arm.flat, s0, options);
  const auto same = fpl::plan_open_loop(flat, s0, options);
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
  ASSERT_EQ(same.status, fpl::SolveStatus::Solved) << same.message;
  EXPECT_NEAR(same.sos.cost_N_s, plan.sos.cost_N_s, 1e-9 * plan.sos.cost_N_s);
  for (double t : {0.0, 0.7, 1.9, 3.0}) {
    const fpl::Jet y = plan.flatOutputJet(t);
    EXPECT_LE((same.flatOutputJet(t) - y).cwiseAbs().maxCoeff(), 1e-7 * (1.0 + y.cwiseAbs().maxCoeff())) << t;
  }
}
