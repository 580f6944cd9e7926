// Plans for a model whose moment arms depend on posture (the shipped elbow: biceps arm 0.02 ->
// 0.04 m -> 0.038 m, brachialis 0.02 -> 0.044 m over 0-143 deg, a pennated triceps (-0.025 m), passive fibres
// in all three): the open-loop plan is reproduced by Simbody; its optimum is checked against an
// independent lower bound (dense_grid_bound.hpp: an LP with C(q) inverted at a dense grid of the
// exact path); and the receding-horizon loop settles at the target.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "../planner/dense_grid_bound.hpp"
#include "../planner/scenario_fixture.hpp"
#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/planner/receding_horizon_controller.hpp"
#include "flatsos/planner/rest_state.hpp"
#include "open_loop_replay.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
using flatsos::test::deg;

namespace {

struct PostureDependentElbow {
  std::shared_ptr<const fp::MusculoskeletalModel> model =
      fp::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) + "/models/elbow_posture_dependent.json");
  fpl::FlatOutputMap flat{model};
  Eigen::VectorXd reserves = Eigen::VectorXd::Constant(3, 10.0);

  fpl::MuscleState rest(double q_deg) const {
    SimTK::State s = model->defaultState();
    fpl::set_minimum_effort_rest_state(flat, s, Eigen::VectorXd::Constant(1, deg(q_deg)), reserves);
    return fpl::muscle_state_of(*model, s);
  }
  fpl::OpenLoopOptions options(double target_deg, double duration_s) const {
    fpl::OpenLoopOptions o = fpl::open_loop_options(fpl::Preset::Paper);
    o.duration_s = duration_s;
    o.target_q_rad = Eigen::VectorXd::Constant(1, deg(target_deg));
    o.reserves_N = reserves;
    return o;
  }
};

}  // namespace

TEST(PostureDependentPlans, OpenLoopPlanIsReproducedBySimbody) {
  const PostureDependentElbow elbow;
  const fpl::MuscleState s0 = elbow.rest(20.0);
  const fpl::OpenLoopPlan plan = fpl::plan_open_loop(elbow.flat, s0, elbow.options(90.0, 1.5));
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
  EXPECT_TRUE(plan.sos.certified);
  // The rest state sits on an SLP vertex: F(0) meets some reserve to rounding.
  EXPECT_GE(plan.check.min_reserve_margin_N, -1e-9);
  const flatsos::test::OpenLoopReplay replay = flatsos::test::replay_open_loop(elbow.flat, s0, plan, 1e-10, 0.01);
  ASSERT_TRUE(replay.sim.finite) << replay.sim.message;
  EXPECT_LT(replay.max_q_error_rad, deg(1e-6));
  EXPECT_LT(replay.max_activation_error, 1e-8);
  EXPECT_LT(replay.max_tendon_length_error_m, 1e-9);
  EXPECT_GE(replay.min_tendon_force_N, 10.0 - 1e-6);
  EXPECT_NEAR(replay.sim.states.rows.back()[1], deg(90), deg(1e-6));
}

TEST(PostureDependentPlans, OptimumIsWithinOnePercentAboveAnIndependentDenseGridBound) {
  const PostureDependentElbow elbow;
  const fpl::MuscleState s0 = elbow.rest(20.0);
  const fpl::OpenLoopPlan plan = fpl::plan_open_loop(elbow.flat, s0, elbow.options(90.0, 1.5));
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
  ASSERT_FALSE(plan.sos.bounds_imposed);  // the bound below is of the reserves-only program
  const double bound = flatsos::test::dense_grid_lower_bound(elbow.flat, plan, s0, elbow.reserves, 601);
  EXPECT_GE(plan.sos.cost_N_s, bound - 1e-6 * bound);
  EXPECT_LE(plan.sos.cost_N_s, 1.01 * bound);
}

TEST(PostureDependentPlans, RecedingHorizonSettlesAtTheTarget) {
  const PostureDependentElbow elbow;
  fpl::RecedingHorizonControllerOptions o;
  o.plan.target_q_rad = Eigen::VectorXd::Constant(1, deg(80));
  o.plan.reserves_N = Eigen::VectorXd::Constant(3, 1.0);
  SimTK::State s = elbow.model->defaultState();
  fpl::set_minimum_effort_rest_state(elbow.flat, s, Eigen::VectorXd::Constant(1, deg(20)), o.plan.reserves_N);
  fpl::RecedingHorizonController controller(elbow.flat, o, elbow.model);
  fp::ClosedLoopOptions loop;
  loop.duration_s = 2.0;
  loop.accuracy = 1e-8;
  const fpl::RecedingHorizonRun run = fpl::run_receding_horizon(controller, s, loop, deg(1));
  ASSERT_TRUE(run.loop.finite);
  EXPECT_EQ(controller.planFailures(), 0);
  ASSERT_GE(run.settling_time_s, 0.0) << "never settled within 1 deg";
  EXPECT_LT(run.settling_time_s, 1.5);
  const double final_error_deg = std::abs(elbow.model->jointAngles(run.loop.final_state)[0] - deg(80)) / deg(1);
  EXPECT_LT(final_error_deg, 0.1);
  // The SLP's rows are exact at each grid posture: 11 postures x 3 muscles.
  EXPECT_EQ(controller.history().front().plan.alpha.size(), 2);
}

TEST(PostureDependentPlans, TheRestStateKeepsActivationsAboveTheFloorWhereAPassiveFibrePullsHarderThanTheReserve) {
  // At full extension the brachialis' stretched fibre pulls about 3.5 N passively: a 1 N reserve
  // alone would ask for less tendon force than that, i.e. a negative activation.
  const PostureDependentElbow elbow;
  const Eigen::VectorXd reserves = Eigen::VectorXd::Constant(3, 1.0);
  SimTK::State s = elbow.model->defaultState();
  fpl::set_minimum_effort_rest_state(elbow.flat, s, Eigen::VectorXd::Constant(1, 0.0), reserves);
  const Eigen::VectorXd a = elbow.model->activations(s);
  for (int j = 0; j < 3; ++j) EXPECT_GE(a[j], elbow.model->muscle(j).getParameters().activation_floor) << "muscle " << j;
  // At rest: nothing moves, and every tendon force meets its reserve.
  elbow.model->system().realize(s, SimTK::Stage::Acceleration);
  EXPECT_LT(s.getUDot().normInf(), 1e-9);
  for (int j = 0; j < 3; ++j) {
    EXPECT_NEAR(elbow.model->muscle(j).getTendonLengthDerivative(s), 0.0, 1e-12);
    EXPECT_GE(flatsos::muscles::tendon_force(elbow.model->muscle(j).getParameters(), elbow.model->tendonLengths(s)[j]),
              1.0 - 1e-9);
  }
}

TEST(PostureDependentPlans, APlanIntoTheElbowsStopIsReproducedBySimbody) {
  // The target lies 0.05 rad beyond the range's upper end (2.5 rad), inside the limit torque's
  // transition: on the way and at the hold the muscles must press against the stop's spring and
  // damper, which Simbody applies as a force element. A planner that did not know the limit would
  // be off by the limit torque (7.3 N m at the hold).
  const PostureDependentElbow elbow;
  const fpl::MuscleState s0 = elbow.rest(120.0);
  const double target_rad = 2.55;
  fpl::OpenLoopOptions o = elbow.options(target_rad / deg(1), 1.0);
  const fpl::OpenLoopPlan plan = fpl::plan_open_loop(elbow.flat, s0, o);
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
  Eigen::VectorXd limit(1);
  elbow.model->pinTree().jointLimitTorques(Eigen::VectorXd::Constant(1, target_rad), Eigen::VectorXd::Zero(1), limit);
  EXPECT_LT(limit[0], -5.0);
  const flatsos::test::OpenLoopReplay replay = flatsos::test::replay_open_loop(elbow.flat, s0, plan, 1e-10, 0.01);
  ASSERT_TRUE(replay.sim.finite) << replay.sim.message;
  EXPECT_LT(replay.max_q_error_rad, deg(1e-6));
  EXPECT_LT(replay.max_activation_error, 1e-8);
  EXPECT_NEAR(replay.sim.states.rows.back()[1], target_rad, deg(1e-6));
}

TEST(PostureDependentPlans, AThreeJointArmWhoseFlatOutputsTheLibraryChoseIsPlannedAndReproducedBySimbody) {
  // Shoulder, elbow and wrist; 8 muscles, four with polynomial paths (two of them over two
  // joints); the model gives no flat_outputs, so the library chooses E and the effort is the sum
  // of normalized tendon forces. Plan, certify, and let Simbody execute it open loop.
  const auto model = fp::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) + "/models/arm_wrist_8_muscles.json");
  const fpl::FlatOutputMap flat(model);
  ASSERT_TRUE(flat.flatOutputs().automatic);
  ASSERT_EQ(flat.effortKind(), fp::EffortWeights::Kind::NormalizedTendonForce);
  const Eigen::VectorXd reserves = Eigen::VectorXd::Constant(8, 10.0);
  SimTK::State s = model->defaultState();
  fpl::set_minimum_effort_rest_state(flat, s, Eigen::Vector3d(0.0, deg(20), 0.0), reserves);
  const fpl::MuscleState s0 = fpl::muscle_state_of(*model, s);
  fpl::OpenLoopOptions o = fpl::open_loop_options(fpl::Preset::Paper);
  o.duration_s = 1.5;
  o.target_q_rad = Eigen::Vector3d(deg(30), deg(80), deg(20));
  o.reserves_N = reserves;
  o.sos.flat_output_spans = 8;
  const fpl::OpenLoopPlan plan = fpl::plan_open_loop(flat, s0, o);
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
  EXPECT_TRUE(plan.sos.certified);
  EXPECT_GE(plan.check.min_excitation, 0.0);
  EXPECT_LE(plan.check.max_excitation, 1.0);
  const flatsos::test::OpenLoopReplay replay = flatsos::test::replay_open_loop(flat, s0, plan, 1e-10, 0.01);
  ASSERT_TRUE(replay.sim.finite) << replay.sim.message;
  EXPECT_LT(replay.max_q_error_rad, deg(1e-6));
  EXPECT_LT(replay.max_activation_error, 1e-8);
  EXPECT_GE(replay.min_tendon_force_N, 10.0 - 1e-6);
}
