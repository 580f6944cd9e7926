// The shortest transfer time (planner/shortest_transfer.hpp) on the paper's transfer: the search's
// bracket is re-planned independently, its plan is executable, the direct-collocation reference
// (a relaxation: any excitations along the same joint path) has a plan wherever the flatness
// planner has one and none a little below a rich basis's shortest time, and a basis that holds
// another's functions is never slower.
#include <gtest/gtest.h>

#include "../planner/executable_plan.hpp"
#include "../planner/scenario_fixture.hpp"
#include "flatsos/planner/collocation.hpp"
#include "flatsos/planner/shortest_transfer.hpp"

namespace fpl = flatsos::planner;
using flatsos::test::open_loop_options;

namespace {

class ShortestTransfer : public ::testing::Test {
 protected:
  flatsos::test::ArmPlanning arm;
  fpl::MuscleState s0 = flatsos::test::open_loop_initial_state(*arm.model);
  flatsos::plugin::ModelWorkspace ws = arm.flat.makeWorkspace();

  fpl::ShortestTransfer search(const fpl::OpenLoopOptions& o, double lower_s, double upper_s) {
    fpl::ShortestTransferOptions so;
    so.lower_s = lower_s;
    so.upper_s = upper_s;
    return fpl::shortest_transfer(arm.flat, ws, s0, o, so);
  }

  // The direct-collocation reference along the degree-8 path of duration T.
  fpl::CollocationResult collocation(double T) {
    auto along = open_loop_options(T);
    along.sos.bounds.enforce = false;
    const fpl::JointPath path = fpl::plan_open_loop(arm.flat, ws, s0, along).path;
    return fpl::solve_collocation_along_path(arm.flat, ws, path, s0, along.reserves_N);
  }
};

}  // namespace

TEST_F(ShortestTransfer, TheQuarticsShortestTimeIsBracketedAndItsPlanIsExecutable) {
  const auto quartic = open_loop_options(3.0);
  const fpl::ShortestTransfer r = search(quartic, 0.5, 3.0);
  ASSERT_EQ(r.status, fpl::SolveStatus::Solved) << r.message;
  EXPECT_FALSE(r.at_lower_end);
  EXPECT_EQ(r.below_status, fpl::SolveStatus::Infeasible) << r.below_message;
  EXPECT_GT(r.shortest_s, r.no_plan_below_s);
  EXPECT_LE(r.shortest_s - r.no_plan_below_s, 1e-3);
  EXPECT_LT(r.shortest_s, 1.5);  // the bounded quartic plans the paper's transfer in 1.5 s
  EXPECT_EQ(r.tried.front().duration_s, 3.0);

  // Both ends again, independently of the search.
  const auto at = fpl::plan_open_loop(arm.flat, ws, s0, open_loop_options(r.shortest_s));
  ASSERT_EQ(at.status, fpl::SolveStatus::Solved) << at.message;
  EXPECT_NEAR(at.sos.cost_N_s, r.plan.sos.cost_N_s, 1e-9 * at.sos.cost_N_s);
  flatsos::test::expect_executable(arm.flat, r.plan, quartic.reserves_N);
  const auto below = fpl::plan_open_loop(arm.flat, ws, s0, open_loop_options(r.no_plan_below_s));
  EXPECT_EQ(below.status, fpl::SolveStatus::Infeasible) << below.message;
  // Every duration the search tried is recorded with the planner's own verdict.
  for (const auto& t : r.tried) EXPECT_NE(t.status, fpl::SolveStatus::Failed) << t.duration_s << " s: " << t.message;
}

TEST_F(ShortestTransfer, CollocationHasAPlanWhereverTheFlatnessPlannerHasOne) {
  const fpl::ShortestTransfer r = search(open_loop_options(3.0), 0.5, 3.0);
  ASSERT_EQ(r.status, fpl::SolveStatus::Solved) << r.message;
  const fpl::CollocationResult c = collocation(r.shortest_s);
  ASSERT_EQ(c.status, fpl::SolveStatus::Solved) << c.message;
  EXPECT_LE(c.cost, r.plan.sos.cost_N_s);  // its excitations include the quartic's
}

TEST_F(ShortestTransfer, ARicherBasisIsNeverSlowerAndNearTheLeastDurationAlongThePath) {
  const fpl::ShortestTransfer quartic = search(open_loop_options(3.0), 0.3, 3.0);
  // Quintic splines on two spans hold every quartic.
  const fpl::ShortestTransfer quintic = search(open_loop_options(3.0, 5, 2), 0.3, 3.0);
  ASSERT_EQ(quartic.status, fpl::SolveStatus::Solved) << quartic.message;
  ASSERT_EQ(quintic.status, fpl::SolveStatus::Solved) << quintic.message;
  EXPECT_LE(quintic.shortest_s, quartic.no_plan_below_s);
  EXPECT_LT(quintic.shortest_s, 0.7);
  // No excitations at all move the arm along the path in 95 % of that time.
  const fpl::CollocationResult c = collocation(0.95 * quintic.shortest_s);
  EXPECT_EQ(c.status, fpl::SolveStatus::Infeasible) << c.message;
}

TEST_F(ShortestTransfer, ReportsNoPlanAtTheLongestDurationAndAPlanAtTheShortest) {
  const fpl::ShortestTransfer none = search(open_loop_options(3.0), 0.5, 1.0);
  EXPECT_EQ(none.status, fpl::SolveStatus::Infeasible);
  EXPECT_NE(none.message.find("no plan at the longest duration, 1 s"), std::string::npos) << none.message;
  EXPECT_EQ(none.plan.status, fpl::SolveStatus::Infeasible);  // the plan at 1 s, with its reason
  EXPECT_EQ(none.shortest_s, 0.0);
  EXPECT_EQ(none.tried.size(), 1u);

  const fpl::ShortestTransfer all = search(open_loop_options(3.0), 2.0, 3.0);
  ASSERT_EQ(all.status, fpl::SolveStatus::Solved) << all.message;
  EXPECT_TRUE(all.at_lower_end);
  EXPECT_EQ(all.shortest_s, 2.0);
  EXPECT_EQ(all.no_plan_below_s, 0.0);
}

TEST_F(ShortestTransfer, BadSearchOptionsAreNamed) {
  auto expect_named = [&](fpl::ShortestTransferOptions so, const std::string& field) {
    try {
      fpl::shortest_transfer(arm.flat, ws, s0, open_loop_options(3.0), so);
      ADD_FAILURE() << field << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  fpl::ShortestTransferOptions so;
  so.lower_s = 0.0;
  expect_named(so, "lower_s");
  so = {};
  so.upper_s = so.lower_s;
  expect_named(so, "upper_s");
  so = {};
  so.scan_ratio = 1.0;
  expect_named(so, "scan_ratio");
  so = {};
  so.tolerance_s = -1.0;
  expect_named(so, "tolerance_s");
  so = {};
  so.max_plans = 1;
  expect_named(so, "max_plans");
}
