#include "flatsos/plugin/io/opensim_kinematics.hpp"

#include <cmath>

namespace flatsos::plugin {

namespace {

void require_supported(const OpenSimJoint& joint) {
  if (joint.type != "WeldJoint" && joint.type != "PinJoint" && joint.type != "SliderJoint" && joint.type != "CustomJoint")
    throw OpenSimModelError(joint.type + " '" + joint.name +
                            "': this joint type is not read (WeldJoint, PinJoint, SliderJoint and CustomJoint are)");
}

// The axis' function argument at q, and the function's value and derivative there.
struct AxisValue {
  double value = 0.0, derivative = 0.0;
  bool driven_by_coordinate = false;
};

AxisValue evaluate(const OpenSimJoint& joint, const OpenSimTransformAxis& axis, const OpenSimCoordinateValues& q,
                   const std::string& rate_coordinate) {
  const std::string where = joint.type + " '" + joint.name + "'." + axis.name;
  if (axis.coordinates.size() > 1)
    throw OpenSimModelError(where + ": driven by " + std::to_string(axis.coordinates.size()) +
                            " coordinates (only functions of one coordinate are evaluated)");
  AxisValue out;
  double x = 0.0;
  if (!axis.coordinates.empty()) {
    const auto it = q.find(axis.coordinates[0]);
    x = it == q.end() ? 0.0 : it->second;
    out.driven_by_coordinate = axis.coordinates[0] == rate_coordinate;
  }
  try {
    out.value = axis.function.value(x);
    if (out.driven_by_coordinate) out.derivative = axis.function.derivative(x);
  } catch (const std::runtime_error& e) {
    throw OpenSimModelError(where + ": " + e.what());
  }
  return out;
}

}  // namespace

Eigen::Isometry3d opensim_joint_transform(const OpenSimJoint& joint, const OpenSimCoordinateValues& q) {
  require_supported(joint);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  for (const auto& axis : joint.axes) {
    const double v = evaluate(joint, axis, q, "").value;
    if (axis.rotation)
      X.linear() = X.linear() * Eigen::AngleAxisd(v, axis.axis).toRotationMatrix();
    else
      X.translation() += v * axis.axis;
  }
  return X;
}

OpenSimJointRate opensim_joint_rate(const OpenSimJoint& joint, const OpenSimCoordinateValues& q, const std::string& coordinate) {
  require_supported(joint);
  OpenSimJointRate rate;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // the rotations before this axis
  double fastest = 0.0;
  for (const auto& axis : joint.axes) {
    const AxisValue v = evaluate(joint, axis, q, coordinate);
    if (axis.rotation) {
      rate.angular += v.derivative * (R * axis.axis);
      if (std::abs(v.derivative) > fastest) {
        fastest = std::abs(v.derivative);
        rate.dominant_axis = (v.derivative > 0.0 ? 1.0 : -1.0) * (R * axis.axis);
      }
      R = R * Eigen::AngleAxisd(v.value, axis.axis).toRotationMatrix();
    } else {
      rate.linear += v.derivative * axis.axis;
    }
  }
  return rate;
}

Eigen::Isometry3d opensim_body_in_ground(const OpenSimModel& model, const std::string& body, const OpenSimCoordinateValues& q) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  std::string current = body;
  for (std::size_t depth = 0; current != "ground"; ++depth) {
    const OpenSimJoint* joint = model.jointOfChild(current);
    if (!joint || depth > model.joints.size())
      throw OpenSimModelError("body '" + current + "' is not connected to ground by joints");
    X = joint->parent_offset * opensim_joint_transform(*joint, q) * joint->child_offset.inverse() * X;
    current = joint->parent_body;
  }
  return X;
}

}  // namespace flatsos::plugin
