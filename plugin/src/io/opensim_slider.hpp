#pragma once
// The importer's sliders (opensim_import.cpp): a kept coordinate whose joint moves with it by one
// translation (a SliderJoint, or a CustomJoint whose translation axes it drives at 1 m per m
// along one direction, everything else of the joint constant) becomes a flatsos slider along that
// direction in ground at the reference posture. Flatsos body frames are parallel to ground there,
// so that direction is also the axis in the parent's frame; a slider does not turn its child,
// so the frames stay parallel to the parent's.

#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "flatsos/plugin/model/model_description.hpp"
#include "opensim_reduction.hpp"

namespace flatsos::plugin::opensim_import {

struct ImportedSlider {
  JointDescription joint;                   ///< type Slider, axis and location as above
  Eigen::Vector3d child_origin_in_ground;   ///< the child's frame origin (the joint's M frame) at the reference
  nlohmann::json provenance;                ///< "exact", "joint_point_error_m", axis, range, ...
};

/// The slider for kept translation `coordinate` of `joint`. `origins` holds each flatsos body's
/// frame origin in ground (the parent's must be there), `members` the OpenSim bodies lumped into
/// the joint's child. Throws OpenSimModelError naming the coordinate and joint when the joint
/// does not translate with it, moves other than 1 m per m of it, or not along one fixed
/// direction over the range.
ImportedSlider import_slider(const OpenSimModel& osim, const Reduction& reduction, const OpenSimImportOptions& options,
                             const OpenSimJoint& joint, const std::string& coordinate,
                             const std::map<std::string, Eigen::Vector3d>& origins, const std::vector<std::string>& members);

/// Where joint `d` (pin or slider, whose point in ground is `joint_origin`) puts, at coordinate
/// q, a point of its child that is at `point` at the reference posture (all in ground).
Eigen::Vector3d placed_by_joint(const JointDescription& d, double q, const Eigen::Vector3d& joint_origin,
                                const Eigen::Vector3d& point);

}  // namespace flatsos::plugin::opensim_import
