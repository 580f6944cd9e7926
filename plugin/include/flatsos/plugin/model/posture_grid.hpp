#pragma once
// Postures over a model's joint ranges, for checks that must hold over the whole range of motion
// (a muscle path longer than its slack tendon; the planner's Assumption 1 with posture-dependent
// moment arms), and the words that name one posture in an error.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <array>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "flatsos/plugin/model/model_description.hpp"

namespace flatsos::plugin {

/// Per joint [lower, upper] in the coordinate's unit (rad for a pin, m for a slider): a box of
/// postures. Empty: the joints' own ranges.
using JointRanges = std::vector<std::array<double, 2>>;

/// Calls visit(q) at each posture of a uniform grid over the ranges of `joints` (every other
/// joint at 0): about `budget` postures, at least the two range ends of each joint (2^k for k
/// joints, which exceeds the budget beyond log2(budget) joints). The ranges are `box`'s when it
/// is given (one per joint of the model), else the joints' own, which every listed joint must
/// then have (JointDescription::hasRange).
void for_each_posture(const ModelDescription& model, const std::vector<int>& joints, long budget,
                      const std::function<void(const Eigen::VectorXd& q_rad)>& visit, const JointRanges& box = {});

/// "elbow = 90.000000 deg, shoulder = 10.000000 deg" for the listed joints of q (a slider's
/// coordinate in m: "rail = 0.100000 m").
std::string describe_posture(const ModelDescription& model, const std::vector<int>& joints, const Eigen::VectorXd& q_rad);
/// The same for every joint of the model.
std::string describe_posture(const ModelDescription& model, const Eigen::VectorXd& q_rad);

/// "r_shoulder_elev -10.000 .. 10.000 deg, r_elbow_flex 5.000 .. 100.000 deg" (a slider's in m).
std::string describe_region(const ModelDescription& model, const JointRanges& box);

/// The joints crossed by some muscle whose moment arms depend on posture, ascending: where
/// C(q) = [R(q); E] changes.
std::vector<int> posture_dependent_joints(const ModelDescription& model);

}  // namespace flatsos::plugin
