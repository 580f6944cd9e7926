#pragma once
// The open-loop planner's study settings: each stage's second opinions, reference formulations,
// tolerances and iteration caps (sos_program_study.hpp, torque_model_study.hpp,
// free_path_study.hpp). The defaults are what plan_open_loop(flat, ..., options) plans with;
// tests, benchmarks and studies change them. The product's programs do not include this header.

#include "flatsos/planner/free_path_study.hpp"
#include "flatsos/planner/open_loop.hpp"
#include "flatsos/planner/shortest_transfer.hpp"
#include "flatsos/planner/sos_program_study.hpp"
#include "flatsos/planner/torque_model_study.hpp"

namespace flatsos::planner {

struct OpenLoopStudyOptions {
  TorqueModelStudyOptions torque;
  SosProgramStudyOptions sos;
  FreePathStudyOptions free_path;
};

/// plan_open_loop with study settings (OpenLoopStudyOptions{}: the product's plan).
OpenLoopPlan plan_open_loop(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const MuscleState& initial,
                            const OpenLoopOptions& options, const OpenLoopStudyOptions& study);
/// The same with a temporary workspace.
OpenLoopPlan plan_open_loop(const FlatOutputMap& flat, const MuscleState& initial, const OpenLoopOptions& options,
                            const OpenLoopStudyOptions& study);

/// shortest_transfer with study settings for its plans.
ShortestTransfer shortest_transfer(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const MuscleState& initial,
                                   const OpenLoopOptions& plan_options, const ShortestTransferOptions& options,
                                   const OpenLoopStudyOptions& study);

}  // namespace flatsos::planner
