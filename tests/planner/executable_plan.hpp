#pragma once
// The checks every bounded open-loop plan must pass: on a 3001-point grid each excitation in
// [0, 1] and activation in (0, 1] to 1e-6, no point outside the muscles' domain, every reserve met,
// and the SOS certificates found.
#include <gtest/gtest.h>

#include "flatsos/planner/motion_planner.hpp"

namespace flatsos::test {

inline void expect_executable(const planner::FlatOutputMap& flat, const planner::OpenLoopPlan& plan,
                              const Eigen::VectorXd& reserves_N) {
  ASSERT_TRUE(plan.Y.has_value()) << plan.message;
  auto ws = flat.makeWorkspace();
  const planner::PlanCheck dense = planner::check_plan(flat, ws, plan.path, *plan.Y, reserves_N, 3001, 1e-6);
  EXPECT_EQ(dense.points_outside_domain, 0) << dense.limiting_violation;
  EXPECT_GE(dense.min_excitation, -1e-6);
  EXPECT_LE(dense.max_excitation, 1.0 + 1e-6);
  EXPECT_GT(dense.min_activation, 0.0);
  EXPECT_LE(dense.max_activation, 1.0 + 1e-6);
  EXPECT_GE(dense.min_reserve_margin_N, -1e-6);
  EXPECT_TRUE(plan.sos.certified) << plan.sos.certified_pieces << " of " << plan.sos.near_active_pieces;
}

}  // namespace flatsos::test
