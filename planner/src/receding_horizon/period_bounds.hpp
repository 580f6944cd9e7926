#pragma once
// Bounded receding-horizon steps: what a step's plan asks of the muscles over its first control
// period kept inside 0 <= n <= 1 and floor <= a <= 1 at the samples the controller applies, by
// construction instead of by the muscle clamping it. With constant flat outputs the tendon forces
// F = C_tau (tau - offset) + C_Y alpha are affine in alpha and their rates do not depend on it,
// so the bounds are smooth rows in the p entries of alpha: the open-loop planner's bound rows and
// sequential LP (bounds/bound_rows.hpp, bounds/sequential_lp.hpp) with the SLP's C_Y alpha >= B, alpha >= 0
// as the linear part, started from the SLP's optimum.

#include "flatsos/planner/receding_horizon_step.hpp"

namespace flatsos::planner::detail {

/// Checks step.alpha() on the first period's samples (step.buffers.excitations / activations
/// hold them afterwards when they are finite) and, when a bound is violated, moves alpha inside:
/// step.slp.alpha, cost, status and message, bounds_imposed and bound_iterations updated.
/// Allocates nothing when the SLP's optimum already meets the bounds. `max_iterations`: the
/// sequential LP's steps.
void impose_period_bounds(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const RecedingHorizonOptions& options,
                          int max_iterations, RecedingHorizonStep& step);

}  // namespace flatsos::planner::detail
