// Bounded plans end solved or infeasible, never "failed", and the verdict is the one the
// independent direct-collocation reference reaches for the same problem. The rows are the
// plans of the strength study (the paper's open-loop start on the arm with each muscle's
// maximum isometric force scaled) that once failed: Clp stopped on errors or called a step LP
// infeasible (rows of 1e86 where a fibre stretched far along the Gaussian force-length curve),
// and a start outside the muscles' domain at a bound point ended the sequential LP at once.
#include <gtest/gtest.h>

#include <array>
#include <memory>

#include "../planner/scenario_fixture.hpp"
#include "flatsos/planner/collocation.hpp"

namespace fpl = flatsos::planner;
namespace fp = flatsos::plugin;
using flatsos::test::open_loop_options;

namespace {

struct Strengths {
  int sample;                   // row of the study (seed 0)
  std::array<double, 6> factor;  // muscle order of the arm's file
};

// The three failures' kinds: "stopped due to errors", "primal infeasible", "the start leaves
// the muscles' domain at a bound point".
constexpr Strengths kFailedOnce[] = {
    {15, {1.171, 1.1872, 0.8059, 1.1455, 1.1925, 1.1829}},
    {22, {1.1239, 1.0242, 0.9154, 0.9652, 1.1272, 1.0506}},
    {123, {0.8731, 1.1128, 0.9087, 1.0263, 1.0584, 0.8799}},
};
// Solved in the study.
constexpr Strengths kSolved{8, {0.8336, 1.1331, 1.1148, 0.8957, 1.1506, 0.8234}};

struct ScaledArm {
  std::shared_ptr<const fp::MusculoskeletalModel> model;
  std::unique_ptr<fpl::FlatOutputMap> flat;
  fpl::MuscleState s0;

  explicit ScaledArm(const Strengths& s) {
    fp::ModelDescription d = flatsos::test::load_arm()->description();
    for (int j = 0; j < d.numMuscles(); ++j) d.muscles[static_cast<std::size_t>(j)].parameters.max_isometric_force_N *= s.factor[static_cast<std::size_t>(j)];
    model = std::make_shared<const fp::MusculoskeletalModel>(std::move(d));
    flat = std::make_unique<fpl::FlatOutputMap>(model);
    s0 = flatsos::test::open_loop_initial_state(*model);
  }

  fpl::OpenLoopPlan plan(int degree, int spans) const { return fpl::plan_open_loop(*flat, s0, open_loop_options(3.0, degree, spans)); }

  // The reference along the plan's joint path (the same degree-8 polynomial for every basis).
  fpl::CollocationResult reference(const fpl::OpenLoopPlan& plan) const {
    auto ws = flat->makeWorkspace();
    fpl::CollocationOptions co;
    co.mesh_intervals = 50;
    return fpl::solve_collocation_along_path(*flat, ws, plan.path, s0, open_loop_options(3.0).reserves_N, co);
  }
};

}  // namespace

TEST(BoundedPlanVerdicts, PlansThatOnceFailedAreInfeasibleAsTheCollocationReferenceFinds) {
  for (const Strengths& s : kFailedOnce) {
    SCOPED_TRACE("study sample " + std::to_string(s.sample));
    const ScaledArm arm(s);
    const fpl::OpenLoopPlan quartic = arm.plan(4, 1);
    EXPECT_EQ(quartic.status, fpl::SolveStatus::Infeasible) << quartic.message;
    EXPECT_NE(quartic.message.find("infeasible"), std::string::npos) << quartic.message;
    const fpl::CollocationResult reference = arm.reference(quartic);
    EXPECT_EQ(reference.status, fpl::SolveStatus::Infeasible) << reference.message;
  }
}

TEST(BoundedPlanVerdicts, ARichBasisReachesTheSameVerdict) {
  // Quintic B-splines on 12 spans (135 free coefficients against the quartic's 4).
  for (const Strengths& s : {kFailedOnce[0], kFailedOnce[1]}) {
    SCOPED_TRACE("study sample " + std::to_string(s.sample));
    const fpl::OpenLoopPlan rich = ScaledArm(s).plan(5, 12);
    EXPECT_EQ(rich.status, fpl::SolveStatus::Infeasible) << rich.message;
  }
}

TEST(BoundedPlanVerdicts, AFeasibleSampleIsSolvedAndNoCheaperThanTheReference) {
  const ScaledArm arm(kSolved);
  const fpl::OpenLoopPlan plan = arm.plan(4, 1);
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
  const fpl::CollocationResult reference = arm.reference(plan);
  ASSERT_EQ(reference.status, fpl::SolveStatus::Solved) << reference.message;
  // The flatness plan is a feasible point of the reference's problem: never below its optimum
  // (beyond the mesh's own error, 0.1 % at 50 intervals).
  EXPECT_GE(plan.sos.cost_N_s, reference.cost * (1.0 - 1e-3));
}
