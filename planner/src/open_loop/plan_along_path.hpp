#pragma once
// The open-loop plan along a fixed joint path (plan.path): the torque model, the SOS program
// with the excitation bounds and certificates, and the dense a-posteriori check. The prescribed
// path's plan and the free path's final plan are both made here.

#include "flatsos/planner/open_loop.hpp"
#include "flatsos/planner/open_loop_study.hpp"
#include "sos/sos_bounds.hpp"

namespace flatsos::planner::detail {

/// Sets every field of `plan` but the path, the warnings and the free-path report. `warm`: where
/// the bounded exchange starts (the free path stage's plan and points).
void plan_along_path(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const FlatOutputBoundary& boundary,
                     const OpenLoopOptions& options, const OpenLoopStudyOptions& study, OpenLoopPlan& plan,
                     const BoundsWarmStart* warm = nullptr);

}  // namespace flatsos::planner::detail
