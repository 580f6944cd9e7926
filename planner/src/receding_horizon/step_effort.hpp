#pragma once
// A receding-horizon step that minimizes a nonlinear effort (squared or cubed excitations,
// activations or stresses: effort.hpp) instead of the paper's linear one. The step's constant
// flat outputs alpha move the tendon forces affinely, and excitations and activations through
// each muscle's inverse (muscles::invert_muscle, with exact gradients), so the effort over the
// horizon is a smooth function of the p entries of alpha. A sequential QP minimizes it: the
// effort's Gauss-Newton model on a grid of the horizon, the reserve rows as they are, the first
// period's excitation bounds linearized (bounds/bound_rows.hpp); each QP by the dual active-set
// method (numerics/dense_qp.hpp); a step is accepted when it stays inside the bounds and lowers
// the effort, else halved.

#include "flatsos/planner/receding_horizon_step.hpp"

namespace flatsos::planner::detail {

/// Moves a solved step's alpha to the minimum of options.effort over the horizon's grid, keeping
/// its reserve rows and first-period bounds: step.slp.alpha, effort_value, effort_iterations and
/// the first period's samples updated (a sample outside the bounds all the same fails the
/// step). Starts from the step's alpha (the SLP's) or the previous step's optimum, whichever is
/// nearer its rows (at most kMaxStartViolation outside) and costs less. Returns false when
/// neither is near enough, the effort cannot be evaluated there, or the QPs do not reach the
/// rows: alpha unchanged, effort_value NaN; the first period's bounds must move alpha inside
/// first (impose_period_bounds), then call again. True (nothing to do) for a step that is not
/// solved or without options.effort.
bool minimize_step_effort(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const RecedingHorizonOptions& options,
                          RecedingHorizonStep& step);

}  // namespace flatsos::planner::detail
