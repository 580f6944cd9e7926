#pragma once
// Where an OpenSim model's bodies are for given coordinate values: each joint's transform from
// its parent offset frame F to its child offset frame M, as Simbody's FunctionBased mobilizer
// builds a CustomJoint (three rotations composed body-fixed, rotation1 first, each about its
// unit axis; translations along their axes in F), a PinJoint about z, a SliderJoint along x.

#include "flatsos/plugin/io/opensim_model.hpp"

#include <map>
#include <string>

namespace flatsos::plugin {

/// Coordinate values by name (rad or m); a coordinate not listed is 0.
using OpenSimCoordinateValues = std::map<std::string, double>;

/// X_FM of the joint. Throws OpenSimModelError naming the joint for a joint type other than
/// WeldJoint, PinJoint, SliderJoint and CustomJoint, an axis driven by more than one coordinate,
/// or a function flatsos does not evaluate.
Eigen::Isometry3d opensim_joint_transform(const OpenSimJoint& joint, const OpenSimCoordinateValues& q);
/// How X_FM changes with one of the joint's coordinates at q: the angular velocity (in F) and
/// the velocity of M's origin (in F) per unit rate of that coordinate.
struct OpenSimJointRate {
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();
  /// The largest single term of `angular`: the rotation axis (in F, unit, signed by the
  /// function's slope) that this coordinate turns fastest, e.g. a walker knee's flexion axis
  /// rather than the tibia's coupled axial rotation. Zero when the coordinate turns nothing.
  Eigen::Vector3d dominant_axis = Eigen::Vector3d::Zero();
};
OpenSimJointRate opensim_joint_rate(const OpenSimJoint& joint, const OpenSimCoordinateValues& q, const std::string& coordinate);
/// The body's frame in ground. Throws OpenSimModelError for an unknown body or one no chain of
/// joints connects to ground.
Eigen::Isometry3d opensim_body_in_ground(const OpenSimModel& model, const std::string& body, const OpenSimCoordinateValues& q);

}  // namespace flatsos::plugin
