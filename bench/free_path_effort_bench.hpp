#pragma once
// Squared excitations (OpenSim Moco's default effort) with the joint path free: the flatness plan
// (reduced quasi-Newton path stage, then the plan along the path) beside the collocation
// reference of the same effort with the path free (200 intervals growing by 1.02), one sample each (the arm's
// path stage takes minutes).

#include <nlohmann/json.hpp>

#include "flatsos/planner/open_loop.hpp"

namespace flatsos::bench {

/// The transfer of `transfer` (duration, target, reserves) from `initial`, the path on 12 spans
/// growing by 1.2.
nlohmann::json free_path_squared_excitations(const planner::FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                             const planner::MuscleState& initial, const planner::OpenLoopOptions& transfer);

}  // namespace flatsos::bench
