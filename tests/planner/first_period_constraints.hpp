#pragma once
// Every constraint of a receding-horizon step's first period as c(alpha) >= 0, from the sampled
// inverse map (independent of the bound rows' analytic gradients): per sample and muscle n,
// 1 - n, a - floor, 1 - a; then C_Y alpha - B (N); then alpha (N). Constant moment arms (the
// map's C_Y). Shared by the bounded-step and effort-step tests.
#include <gtest/gtest.h>

#include <Eigen/Core>

#include "flatsos/planner/receding_horizon_step.hpp"

namespace flatsos::test {

inline Eigen::VectorXd first_period_constraints(const planner::FlatOutputMap& flat, plugin::ModelWorkspace& ws,
                                                const planner::PeriodExcitationBounds& b,
                                                const planner::RecedingHorizonStep& step, const Eigen::VectorXd& alpha) {
  planner::PlanExcitationScratch scratch;
  Eigen::MatrixXd n, a;
  EXPECT_TRUE(planner::sample_plan_excitations(flat, ws, step.path, alpha, step.torque_offset_N_m, 0.0,
                                               b.period_s / (b.samples - 1), b.samples, scratch, n, &a));
  const int m = flat.numMuscles();
  Eigen::VectorXd c(4 * n.size() + m + alpha.size());
  int k = 0;
  for (Eigen::Index i = 0; i < n.rows(); ++i)
    for (int j = 0; j < m; ++j) {
      const double floor = flat.model().muscle(j).getParameters().activation_floor;
      c[k++] = n(i, j);
      c[k++] = 1.0 - n(i, j);
      c[k++] = a(i, j) - floor;
      c[k++] = 1.0 - a(i, j);
    }
  c.segment(k, m) = flat.CY() * alpha - step.bound_N;
  c.tail(alpha.size()) = alpha;
  return c;
}

}  // namespace flatsos::test
