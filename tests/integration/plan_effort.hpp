#pragma once
// A plan's squared excitations recomputed independently of the planner: Simpson's rule over
// uniform intervals of sum_j n_j^2 from the exact inverse map (not the planner's torque model
// nor its quadrature).
#include "flatsos/planner/motion_planner.hpp"
#include "flatsos/planner/planned_excitation.hpp"

namespace flatsos::test {

/// `intervals` must be even.
inline double squared_excitations_of(const planner::FlatOutputMap& flat, const planner::OpenLoopPlan& plan, int intervals) {
  const auto planned = planner::PlannedExcitation::create(flat, plan.path, *plan.Y);
  const double T = plan.path.duration_s, h = T / intervals;
  double sum = 0.0;
  for (int i = 0; i <= intervals; ++i) {
    const double w = (i == 0 || i == intervals) ? 1.0 : (i % 2 ? 4.0 : 2.0);
    sum += w * planned->at(i * h).excitation.squaredNorm();
  }
  return sum * h / 3.0;
}

}  // namespace flatsos::test
