#pragma once
// Flat outputs for a task. Assumption 1 must hold wherever the task goes; OpenSim's coordinate
// ranges are often wider than any choice of E can serve (arm26's shoulder elevated so far that
// C(q) = [R(q); E] turns singular for every E the library tries). A task that stays in a box of
// postures needs E only there: the box its postures span, widened by a margin for the path
// between them and a controller's overshoot.

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/plugin/model/posture_grid.hpp"

namespace flatsos::planner {

/// How far the task's region reaches beyond its postures: a pin's, a slider's.
constexpr double kTaskRegionMargin_rad = 10.0 * 3.14159265358979323846 / 180.0;
constexpr double kTaskRegionMargin_m = 0.02;

/// The box a task visiting `postures` (one value per joint each, rad or m) needs: per joint the
/// postures' span widened by the margin, clipped to the joint's range. Throws
/// std::invalid_argument for a posture of the wrong size or a non-finite value.
plugin::JointRanges task_region(const plugin::ModelDescription& model, const std::vector<Eigen::VectorXd>& postures);

/// The model's flat outputs (its own, else the library's choice) over the joint ranges when they
/// satisfy Assumption 1 there; otherwise over task_region(postures) (FlatOutputChoice::region
/// says so). Throws FlatnessError giving both failures when neither works.
FlatOutputMap flat_outputs_for_task(std::shared_ptr<const plugin::MusculoskeletalModel> model,
                                    const std::vector<Eigen::VectorXd>& postures);

}  // namespace flatsos::planner
