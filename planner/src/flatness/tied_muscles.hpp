#pragma once
// Tied muscles: muscles whose moment-arm columns agree in every posture and whose effort weights
// agree. A linear effort w^T F then prices every split of their shared load alike, the effort LP
// has a whole optimal face, and the simplex may pick a different vertex of it in each exchange
// round: the load shuttles between the tied muscles (arm26's TRIlat and TRImed), the exchange
// chases the new violations without converging, and the force derivatives of the shuttle push
// the excitations out of their bounds. A deterministic tie-break (a slightly lower price for
// each later muscle of a group) makes the optimum unique and leaves untied problems as they are.

#include <vector>

#include <Eigen/Core>

#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace flatsos::planner::detail {

/// Moment arms and weights agree to this fraction of the group's largest moment arm and weight.
constexpr double kTieRelativeTolerance = 1e-6;
/// Each earlier muscle of a group costs this fraction more per newton than the one after it.
constexpr double kTieBreakRelativeWeight = 1e-3;

/// The groups (two or more muscles, ascending indices) whose moment-arm columns agree, with
/// constant moment arms in A, else on a grid over the ranges of the joints whose moment arms
/// depend on posture, and whose effort weights agree.
std::vector<std::vector<int>> tied_muscle_groups(const plugin::MusculoskeletalModel& model, const Eigen::VectorXd& weights,
                                                 double relative_tolerance = kTieRelativeTolerance);

/// The effort weights the effort LPs price forces with: `weights`, with the k-th of the K muscles
/// of each tied group (k = 0 .. K - 1) weighing (1 + (K - 1 - k) relative_step) times as much.
Eigen::VectorXd tie_broken_effort_weights(const plugin::MusculoskeletalModel& model, const Eigen::VectorXd& weights,
                                          double relative_step = kTieBreakRelativeWeight);

}  // namespace flatsos::planner::detail
