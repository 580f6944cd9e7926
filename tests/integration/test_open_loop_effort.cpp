// Open-loop plans that minimize a nonlinear effort (squared excitations, OpenSim Moco's default)
// along the prescribed joint path, against the collocation reference's optimum of the same
// effort along the same path, on the 1-joint elbow and the paper's arm. The plan's effort is
// recomputed independently from the exact inverse map on a dense grid (Simpson), its bounds and
// reserves checked densely with its certificates, its load shared between synergists, and it is
// replayed open loop by Simbody.
#include <gtest/gtest.h>

#include <iostream>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "../planner/executable_plan.hpp"
#include "../planner/scenario_fixture.hpp"
#include "flatsos/planner/collocation.hpp"
#include "flatsos/planner/effort.hpp"
#include "plan_effort.hpp"
#include "flatsos/planner/motion_planner.hpp"
#include "flatsos/planner/planned_excitation.hpp"
#include "flatsos/planner/rest_state.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"
#include "flatsos/plugin/model/model_workspace.hpp"
#include "arm26_transfer.hpp"
#include "open_loop_replay.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
using flatsos::test::squared_excitations_of;

namespace {

// The share of `points` uniform times at which muscle j pulls more than `force_N`.
double share_above(const fpl::FlatOutputMap& flat, const fpl::OpenLoopPlan& plan, int j, double force_N, int points) {
  const auto planned = fpl::PlannedExcitation::create(flat, plan.path, *plan.Y);
  int above = 0;
  for (int i = 0; i < points; ++i) above += planned->at(plan.path.duration_s * i / (points - 1)).tendon_force_N[j] > force_N;
  return static_cast<double>(above) / points;
}

// Simpson's rule of an effort of the seam (PowerEffort's terms, weights 1) from the exact inverse
// map of the plan.
double effort_of(const fpl::FlatOutputMap& flat, const fpl::OpenLoopPlan& plan, const fpl::Effort& effort,
                 int intervals) {
  const auto planned = fpl::PlannedExcitation::create(flat, plan.path, *plan.Y);
  const double T = plan.path.duration_s, h = T / intervals;
  double sum = 0.0;
  for (int i = 0; i <= intervals; ++i) {
    const double w = (i == 0 || i == intervals) ? 1.0 : (i % 2 ? 4.0 : 2.0);
    const fpl::MusclePoint mp = planned->at(i * h);
    for (int j = 0; j < flat.numMuscles(); ++j)
      sum += w * effort.muscleTerm(j, flat.model().muscle(j).getParameters(), mp.tendon_force_N[j], mp.activation[j],
                                   mp.excitation[j]).value;
  }
  return sum * h / 3.0;
}

fpl::FlatOutputMap elbow_map(fpl::MuscleState& s0, fpl::OpenLoopOptions& o) {
  const fp::ModelDescription d = fp::load_model_file(std::string(FLATSOS_SOURCE_DIR) + "/models/elbow_1dof.json");
  const auto model = std::make_shared<const fp::MusculoskeletalModel>(d);
  const fpl::FlatOutputMap flat(model);
  const fp::ScenarioDescription& s = *d.scenario("open_loop");
  o.duration_s = s.duration_s;
  o.target_q_rad = s.target_q_rad;
  o.reserves_N = Eigen::VectorXd::Constant(3, s.reserves_N[0]);
  SimTK::State state = model->defaultState();
  fpl::set_minimum_effort_rest_state(flat, state, s.q0_rad, o.reserves_N);
  s0 = fpl::muscle_state_of(*model, state);
  return flat;
}

struct SquaredPlan {
  fpl::OpenLoopPlan plan;
  double reference = 0.0;   // the collocation optimum along the plan's path
  double recomputed = 0.0;  // the plan's effort from the exact inverse map
  std::vector<double> replay_error_rad;  // Simbody's open-loop replay at accuracies 1e-10 and 1e-12
};

// The squared-excitation plan, checked executable and replayed, and its collocation reference.
SquaredPlan plan_squared(const fpl::FlatOutputMap& flat, const fpl::MuscleState& s0, fpl::OpenLoopOptions o,
                         const char* name) {
  o.effort = fpl::effort_named("excitation_squared");
  SquaredPlan out{fpl::plan_open_loop(flat, s0, o), 0.0, 0.0, {}};
  const fpl::OpenLoopPlan& plan = out.plan;
  EXPECT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
  if (plan.status != fpl::SolveStatus::Solved) return out;
  EXPECT_EQ(plan.sos.effort_name, "excitation_squared");
  EXPECT_EQ(plan.sos.effort_unit, "s");
  flatsos::test::expect_executable(flat, plan, o.reserves_N);
  for (const double accuracy : {1e-10, 1e-12}) {
    const auto replay = flatsos::test::replay_open_loop(flat, s0, plan, accuracy, 0.01);
    EXPECT_TRUE(replay.sim.finite) << replay.sim.message;
    out.replay_error_rad.push_back(replay.max_q_error_rad);
  }

  auto workspace = flat.makeWorkspace();
  fpl::CollocationOptions co;
  co.effort = o.effort;
  co.mesh_intervals = 200;  // converged: 400 intervals moved the arm's optimum by 2e-4 of it
  const fpl::CollocationResult reference =
      fpl::solve_collocation_along_path(flat, workspace, plan.path, s0, o.reserves_N, co);
  EXPECT_EQ(reference.status, fpl::SolveStatus::Solved) << reference.message;
  out.reference = reference.cost;
  out.recomputed = squared_excitations_of(flat, plan, 3000);
  std::cout << name << ": plan " << plan.sos.effort_value << " s (recomputed " << out.recomputed << "), collocation "
            << out.reference << " s (" << 100.0 * (plan.sos.effort_value / out.reference - 1.0) << " % above) in "
            << reference.setup_seconds + reference.solve_seconds << " s; the plan in " << plan.setup_seconds + plan.solve_seconds
            << " s (" << plan.sos.effort_rounds << " rounds, " << plan.sos.effort_iterations << " QP steps, "
            << plan.sos.effort_seconds << " s); Simbody replay at accuracy 1e-10 / 1e-12: " << out.replay_error_rad[0] * 180.0 / M_PI << " / "
            << out.replay_error_rad[1] * 180.0 / M_PI << " deg\n";
  return out;
}

}  // namespace

TEST(OpenLoopEffort, SquaredExcitationsOnTheElbowShareTheLoadAndMatchTheCollocationOptimum) {
  fpl::MuscleState s0;
  fpl::OpenLoopOptions o;
  const fpl::FlatOutputMap flat = elbow_map(s0, o);
  const Eigen::VectorXd reserves = o.reserves_N;
  const SquaredPlan squared = plan_squared(flat, s0, o, "elbow");
  ASSERT_EQ(squared.plan.status, fpl::SolveStatus::Solved);
  const double effort = squared.plan.sos.effort_value;
  EXPECT_NEAR(squared.recomputed, effort, 1e-3 * effort);
  EXPECT_LT(effort, 1.01 * squared.reference);
  EXPECT_GT(effort, 0.999 * squared.reference);  // a plan below the optimum would be a wrong effort
  EXPECT_LT(squared.replay_error_rad[0], flatsos::test::deg(1e-4));

  // The linear effort leaves the brachialis (muscle 1) at its reserve all along; the squared one
  // has it pull well above it over most of the motion, as the collocation optimum does
  // (test_effort_pipeline.cpp).
  const fpl::OpenLoopPlan linear = fpl::plan_open_loop(flat, s0, o);
  ASSERT_EQ(linear.status, fpl::SolveStatus::Solved) << linear.message;
  const double above_linear = share_above(flat, linear, 1, 1.05 * reserves[1], 301);
  const double above_squared = share_above(flat, squared.plan, 1, 1.05 * reserves[1], 301);
  std::cout << "  brachialis above its reserve at " << 100.0 * above_linear << " % (linear) and " << 100.0 * above_squared
            << " % (squared) of the motion\n";
  EXPECT_LT(above_linear, 0.05);
  EXPECT_GT(above_squared, 0.4);
}

TEST(OpenLoopEffort, SquaredExcitationsOnThePapersArmMatchTheCollocationOptimum) {
  const flatsos::test::ArmPlanning arm;
  fpl::OpenLoopOptions o;  // the default basis
  const fpl::OpenLoopOptions paper = flatsos::test::open_loop_options();
  o.duration_s = paper.duration_s;
  o.target_q_rad = paper.target_q_rad;
  o.reserves_N = paper.reserves_N;
  const SquaredPlan squared = plan_squared(arm.flat, flatsos::test::open_loop_initial_state(*arm.model), o, "paper's arm");
  ASSERT_EQ(squared.plan.status, fpl::SolveStatus::Solved);
  const double effort = squared.plan.sos.effort_value;
  EXPECT_NEAR(squared.recomputed, effort, 1e-3 * effort);
  EXPECT_LT(effort, 1.01 * squared.reference);
  EXPECT_GT(effort, 0.999 * squared.reference);
  // Upright is an unstable rest of this arm, and the squared optimum co-contracts little: open loop,
  // the replay's error grows about 6.5-fold per second (1e-10 rad at 0.02 s, 1e-9 deg at 1 s,
  // 5e-3 deg at 3 s with accuracy 1e-10). It follows the integrator's accuracy, so the plan is
  // what the muscles execute; held to 1e-4 deg it needs a feedback (the receding horizon).
  EXPECT_LT(squared.replay_error_rad[1], flatsos::test::deg(1e-3));
  EXPECT_GT(squared.replay_error_rad[0], 5.0 * squared.replay_error_rad[1]);
}

// Every nonlinear effort of the seam plans on the elbow: what the plan reports is the effort of
// its own muscles (recomputed from the exact inverse map), and no more than the linear plan's
// muscles cost under that effort.
TEST(OpenLoopEffort, EveryEffortOfTheFieldPlansWhatItReports) {
  fpl::MuscleState s0;
  fpl::OpenLoopOptions o;
  const fpl::FlatOutputMap flat = elbow_map(s0, o);
  const fpl::OpenLoopPlan linear = fpl::plan_open_loop(flat, s0, o);
  ASSERT_EQ(linear.status, fpl::SolveStatus::Solved) << linear.message;
  for (const std::string& name : fpl::effort_names()) {
    if (name == "tendon_force") continue;
    o.effort = fpl::effort_named(name);
    const fpl::OpenLoopPlan plan = fpl::plan_open_loop(flat, s0, o);
    ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << name << ": " << plan.message;
    EXPECT_EQ(plan.sos.effort_name, name);
    const double recomputed = effort_of(flat, plan, *o.effort, 3000), of_linear = effort_of(flat, linear, *o.effort, 3000);
    std::cout << name << ": " << plan.sos.effort_value << " s (recomputed " << recomputed << "; the linear plan's "
              << of_linear << ")\n";
    EXPECT_NEAR(recomputed, plan.sos.effort_value, 1e-3 * plan.sos.effort_value) << name;
    EXPECT_LT(plan.sos.effort_value, of_linear) << name;
  }
}

// With the joint path free the squared-excitation plan moves the path too: it costs less than
// along the prescribed path, comes within 2 % above the collocation reference's free optimum of
// the same effort (and not below it), keeps its bounds and is replayed by Simbody.
TEST(OpenLoopEffort, SquaredExcitationsWithTheJointPathFreeMatchTheCollocationsFreeOptimum) {
  fpl::MuscleState s0;
  fpl::OpenLoopOptions o;
  const fpl::FlatOutputMap flat = elbow_map(s0, o);
  o.effort = fpl::effort_named("excitation_squared");
  const fpl::OpenLoopPlan prescribed = fpl::plan_open_loop(flat, s0, o);
  ASSERT_EQ(prescribed.status, fpl::SolveStatus::Solved) << prescribed.message;
  o.free_path.enabled = true;
  // The path on 12 spans, each 1.2 times the one before (the transfer is fast early): the free
  // optimum 1.05 % above the reference's; 6 uniform spans (the default) end 7.2 % above, 12
  // uniform 2.1 %, 12 growing by 1.4 1.4 %.
  o.free_path.spans = 12;
  o.free_path.span_growth = 1.2;
  const fpl::OpenLoopPlan plan = fpl::plan_open_loop(flat, s0, o);
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
  EXPECT_TRUE(plan.free_path.optimized);
  auto workspace = flat.makeWorkspace();
  fpl::CollocationOptions co;
  co.effort = o.effort;
  co.mesh_intervals = 200;
  const fpl::CollocationResult reference =
      fpl::solve_collocation_free_path(flat, workspace, prescribed.path, s0, o.reserves_N, co);
  ASSERT_EQ(reference.status, fpl::SolveStatus::Solved) << reference.message;
  const double effort = plan.sos.effort_value, recomputed = squared_excitations_of(flat, plan, 3000);
  std::cout << "elbow, free path: plan " << effort << " s (recomputed " << recomputed << "; prescribed path "
            << prescribed.sos.effort_value << "; path stage " << plan.free_path.cost_at_points_N_s << " in "
            << plan.free_path.seconds << " s, " << plan.free_path.path_iterations << " steps, " << plan.free_path.rounds
            << " rounds), collocation " << reference.cost << " s (" << 100.0 * (effort / reference.cost - 1.0)
            << " % above) in " << reference.setup_seconds + reference.solve_seconds << " s\n";
  EXPECT_NEAR(recomputed, effort, 1e-3 * effort);
  EXPECT_LT(effort, prescribed.sos.effort_value);
  EXPECT_LT(effort, 1.02 * reference.cost);
  EXPECT_GT(effort, 0.999 * reference.cost);
  flatsos::test::expect_executable(flat, plan, o.reserves_N);
  const auto replay = flatsos::test::replay_open_loop(flat, s0, plan, 1e-10, 0.01);
  ASSERT_TRUE(replay.sim.finite) << replay.sim.message;
  EXPECT_LT(replay.max_q_error_rad, flatsos::test::deg(1e-4));
}


namespace {

using flatsos::test::Arm26Transfer;
using flatsos::test::arm26_transfer;

// The squared-excitation plan of the transfer: solved on uniform spans after the default graded
// ones found none, with a warning that says so, and executable.
fpl::OpenLoopPlan plan_arm26_squared(const Arm26Transfer& a) {
  fpl::OpenLoopOptions o = a.options;
  o.effort = fpl::effort_named("excitation_squared");
  fpl::OpenLoopPlan plan = fpl::plan_open_loop(*a.flat, a.s0, o);
  EXPECT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
  if (plan.status != fpl::SolveStatus::Solved) return plan;
  EXPECT_EQ(plan.flat_output_span_growth, 1.0);
  EXPECT_FALSE(plan.warnings.empty());
  if (!plan.warnings.empty()) {
    EXPECT_NE(plan.warnings.back().find("planned again on uniform spans"), std::string::npos) << plan.warnings.back();
  }
  flatsos::test::expect_executable(*a.flat, plan, o.reserves_N);
  return plan;
}

}  // namespace

// OpenSim's arm26 as downloaded (Thelen 2003 muscles, wrapping paths fitted). On the graded spans
// a nonlinear effort gets by default, the effort's sequential QP finds no plan: Thelen's
// force-velocity slope doubles at zero fibre velocity, so the excitation, and its bounds, jump
// where a fibre's velocity changes sign. On uniform spans the plan costs less than the linear
// effort's muscles under the same effort and is replayed by Simbody.
TEST(OpenLoopEffort, Arm26sSquaredExcitationsArePlannedOnUniformSpansWhereTheGradedOnesFindNone) {
  const Arm26Transfer a = arm26_transfer({});
  const fpl::OpenLoopPlan linear = fpl::plan_open_loop(*a.flat, a.s0, a.options);
  ASSERT_EQ(linear.status, fpl::SolveStatus::Solved) << linear.message;
  const fpl::OpenLoopPlan plan = plan_arm26_squared(a);
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved);
  // Recomputed by Simpson's rule: 0.249402 / 0.249365 / 0.249410 / 0.249395 s with 1000 / 3000 /
  // 9000 / 30000 intervals (the jumps keep it from converging faster). The plan's own Gauss points
  // (4 per segment) see the jumps as if smooth: 0.248522 s, 0.35 % below. With DeGroote-Fregly's
  // smooth muscles (below) the two agree to 1e-6.
  const double recomputed = squared_excitations_of(*a.flat, plan, 3000);
  const double linears = squared_excitations_of(*a.flat, linear, 3000);
  EXPECT_NEAR(recomputed, plan.sos.effort_value, 5e-3 * plan.sos.effort_value);
  EXPECT_LT(recomputed, 0.9 * linears);
  const auto replay = flatsos::test::replay_open_loop(*a.flat, a.s0, plan, 1e-10, 0.01);
  EXPECT_TRUE(replay.sim.finite) << replay.sim.message;
  EXPECT_LT(replay.max_q_error_rad, 1e-4 * M_PI / 180.0);
  std::cout << "arm26, squared excitations: " << plan.sos.effort_value << " s (recomputed " << recomputed
            << "; the linear effort's muscles " << linears << ") in " << plan.setup_seconds + plan.solve_seconds
            << " s; Simbody replay " << replay.max_q_error_rad * 180.0 / M_PI << " deg\n";
}

// The same transfer with arm26's muscles replaced as Moco replaces them (DeGroote-Fregly 2016): on
// the graded spans the bounded exchange keeps adding reserve points; on uniform spans the plan's
// effort is its muscles' to 1e-5.
TEST(OpenLoopEffort, Arm26WithDeGrooteFreglyMusclesIsPlannedOnUniformSpansWhereTheGradedOnesFindNone) {
  fp::OpenSimFileOptions file;
  file.degroote_fregly2016_muscles = true;
  const Arm26Transfer a = arm26_transfer(file);
  const fpl::OpenLoopPlan plan = plan_arm26_squared(a);
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved);
  const double recomputed = squared_excitations_of(*a.flat, plan, 3000);
  EXPECT_NEAR(recomputed, plan.sos.effort_value, 1e-5 * plan.sos.effort_value);
  std::cout << "arm26 with DeGroote-Fregly muscles, squared excitations: " << plan.sos.effort_value << " s (recomputed "
            << recomputed << ") in " << plan.setup_seconds + plan.solve_seconds << " s\n";
}
