// Who owns what: plans, maps and controllers keep what they need alive (no dangling reference
// from temporaries), and the immutable model and map serve several threads at once.
#include <gtest/gtest.h>

#include <thread>

#include "flatsos/planner/receding_horizon_study.hpp"
#include "flatsos/planner/planned_excitation.hpp"
#include "flatsos/planner/receding_horizon_controller.hpp"
#include "flatsos/planner/rest_state.hpp"
#include "scenario_fixture.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
using flatsos::test::deg;

namespace {
fpl::RecedingHorizonOptions rh_options() {
  fpl::RecedingHorizonOptions o;
  o.target_q_rad = Eigen::Vector2d(deg(80), deg(80));
  o.reserves_N = Eigen::VectorXd::Constant(6, 1.0);
  return o;
}
}  // namespace

// Regression: the signals of a plan, stored in a SimTK::State, used to point into a
// FlatOutputMap (and through it the model) that the caller had already destroyed.
TEST(Ownership, PlanSignalsOutliveEverythingTheyWereMadeFrom) {
  SimTK::State state;
  std::shared_ptr<const fp::ExcitationSignal> signal;
  double expected = 0.0;
  {
    auto model = flatsos::test::load_arm();
    const auto plan = fpl::plan_open_loop(fpl::FlatOutputMap(model), flatsos::test::open_loop_initial_state(*model),
                                          flatsos::test::open_loop_options());
    ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
    const auto excitation = fpl::PlannedExcitation::create(fpl::FlatOutputMap(model), plan.path, *plan.Y);  // a temporary map
    expected = excitation->at(1.3).excitation[2];
    signal = excitation->signal(2);
    state = model->defaultState();
    model->muscle(2).setExcitationSignal(state, signal);
  }  // the model handle, the map, the plan and the excitation object are gone
  EXPECT_EQ(signal.use_count(), 2);  // ours and the State's
  EXPECT_DOUBLE_EQ(signal->value(1.3), expected);
  EXPECT_GT(expected, 0.0);
}

TEST(Ownership, AControllerMadeFromATemporaryMapRuns) {
  auto model = flatsos::test::load_arm();
  fpl::RecedingHorizonControllerOptions o;
  o.plan = rh_options();
  fpl::RecedingHorizonController controller(fpl::FlatOutputMap(model), o);  // used to dangle
  SimTK::State s = model->defaultState();
  fpl::set_minimum_effort_rest_state(controller.flat(), s, Eigen::Vector2d(deg(20), deg(20)), o.plan.reserves_N);
  model.reset();  // the controller shares the model
  const auto& rec = controller.step(s);
  EXPECT_EQ(rec.status, fpl::SolveStatus::Solved) << rec.message;
  EXPECT_FALSE(rec.plan.empty());
}

TEST(Ownership, CopiesOfAMapAreIndependentValues) {
  auto model = flatsos::test::load_arm();
  fpl::FlatOutputMap a(model);
  const fpl::FlatOutputMap b = a;  // copy
  a = fpl::FlatOutputMap(model, Eigen::MatrixXd(b.E().colwise().reverse()));
  EXPECT_NE((a.E() - b.E()).norm(), 0.0);
  EXPECT_EQ(&a.model(), &b.model());  // one shared model
}

// Two threads plan on the same model and map at once and get exactly the single-threaded
// results (the model and map used to share one mutable scratch State).
TEST(Ownership, TwoThreadsPlanOnTheSameModelAtOnce) {
  const flatsos::test::ArmPlanning arm;
  const auto s0 = flatsos::test::open_loop_initial_state(*arm.model);
  const auto options = flatsos::test::open_loop_options();
  const auto reference = fpl::plan_open_loop(arm.flat, s0, options);
  ASSERT_EQ(reference.status, fpl::SolveStatus::Solved);
  const Eigen::Vector2d q(deg(20), deg(30)), qd(0.2, -0.1);
  const auto rh_reference = fpl::plan_receding_horizon_step(arm.flat, q, qd, rh_options());

  std::vector<fpl::OpenLoopPlan> plans(2);
  std::vector<std::vector<fpl::RecedingHorizonStep>> steps(2);
  std::vector<std::thread> threads;
  for (int i = 0; i < 2; ++i)
    threads.emplace_back([&, i] {
      plans[i] = fpl::plan_open_loop(arm.flat, s0, options);
      for (int k = 0; k < 50; ++k) steps[i].push_back(fpl::plan_receding_horizon_step(arm.flat, q, qd, rh_options()));
    });
  for (auto& t : threads) t.join();
  for (int i = 0; i < 2; ++i) {
    ASSERT_EQ(plans[i].status, fpl::SolveStatus::Solved) << plans[i].message;
    EXPECT_EQ(plans[i].sos.cost_N_s, reference.sos.cost_N_s);
    ASSERT_TRUE(plans[i].Y && reference.Y);
    EXPECT_EQ(plans[i].Y->coefficients(), reference.Y->coefficients());
    for (const auto& step : steps[i]) {
      EXPECT_EQ(step.alpha(), rh_reference.alpha());
      EXPECT_EQ(step.tau_min, rh_reference.tau_min);
      EXPECT_EQ(step.tau_max, rh_reference.tau_max);
    }
  }
}

TEST(Ownership, WorkspacesBelongToTheirModel) {
  const auto a = flatsos::test::load_arm();
  const auto b = flatsos::test::load_arm();
  fp::ModelWorkspace ws = a->makeWorkspace();
  const Eigen::Vector2d zero = Eigen::Vector2d::Zero();
  EXPECT_NO_THROW(a->inverseDynamics(ws, zero, zero, zero));
  try {
    b->inverseDynamics(ws, zero, zero, zero);
    FAIL() << "a workspace of another model was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("another model"), std::string::npos) << e.what();
  }
}

// The SLP's warm start (an optional value): from the optimum Ipopt needs no more iterations than
// from the appendix construction and ends at the same alpha.
TEST(Ownership, WarmStartedSlpReachesTheSameOptimumInNoMoreIterations) {
  const flatsos::test::ArmPlanning arm;
  const Eigen::Vector2d q(deg(20), deg(20)), qd = Eigen::Vector2d::Zero();
  auto o = rh_options();
  const auto cold = fpl::plan_receding_horizon_step(arm.flat, q, qd, o);
  ASSERT_EQ(cold.status, fpl::SolveStatus::Solved);
  ASSERT_FALSE(cold.slp.used_fallback);
  fpl::RecedingHorizonStudyOptions study;
  study.slp_by_ipopt = true;
  const auto cold_ipopt = fpl::plan_receding_horizon_step(arm.flat, q, qd, o, study);
  ASSERT_EQ(cold_ipopt.status, fpl::SolveStatus::Solved);
  ASSERT_FALSE(cold_ipopt.slp.used_fallback);
  EXPECT_GT(cold_ipopt.slp.iterations, 0);
  study.warm_start = cold.alpha();
  const auto warm = fpl::plan_receding_horizon_step(arm.flat, q, qd, o, study);
  ASSERT_EQ(warm.status, fpl::SolveStatus::Solved);
  EXPECT_FALSE(warm.slp.used_fallback);
  EXPECT_LT((warm.alpha() - cold.alpha()).norm(), 1e-6 * (1 + cold.alpha().norm()));
  EXPECT_LE(warm.slp.iterations, cold_ipopt.slp.iterations);
  study.warm_start = Eigen::VectorXd::Constant(3, 1.0);
  EXPECT_THROW(fpl::plan_receding_horizon_step(arm.flat, q, qd, o, study), std::invalid_argument);
}
