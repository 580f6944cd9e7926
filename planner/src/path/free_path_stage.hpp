#pragma once
// The free joint path stage of the open-loop planner (free_path.hpp): from the prescribed path's
// plan, the path optimized (path/free_path.hpp), then the plan along it, its torque model refined
// while that plan fails or costs clearly more than the path stage found.

#include <Eigen/Core>

#include "flatsos/planner/open_loop.hpp"
#include "flatsos/planner/open_loop_study.hpp"

namespace flatsos::planner::detail {

/// Throws std::invalid_argument naming the field for options the free path cannot plan with
/// (nothing when options.free_path is off).
void validate_free_path_options(const FlatOutputMap& flat, const OpenLoopOptions& options,
                                const OpenLoopStudyOptions& study);

/// The flat outputs' spans of the plan that starts the path stage: S / f for the largest divisor
/// f of S = `spans` that leaves at least `min_spans` (S / f spans growing by growth^f have every
/// f-th breakpoint of the S spans, so their splines are among the S spans'). `fewest`: the spans
/// that leave the flat outputs a free coefficient besides their boundary conditions. 0 min_spans:
/// S itself.
int start_flat_output_spans(int spans, int min_spans, int fewest);

/// `plan`: the prescribed path's plan (in the basis of `start_spans` spans); on return the plan
/// along the optimized path with its free-path report, or the prescribed one with the reason the
/// path was not optimized. `initial_q_jet`: the joints' jet the initial state fixes.
void plan_along_free_path(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const FlatOutputBoundary& boundary,
                          const Eigen::MatrixXd& initial_q_jet, const OpenLoopOptions& options,
                          const OpenLoopStudyOptions& study, int start_spans, OpenLoopPlan& plan);

}  // namespace flatsos::planner::detail
