#include "opensim_slider.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "flatsos/plugin/io/opensim_kinematics.hpp"

namespace flatsos::plugin::opensim_import {

namespace {

constexpr int kRangeSamples = 60;
// A slider whose bodies follow OpenSim's joint this closely over the range is exact (rounding).
constexpr double kExactSliderTolerance_m = 1e-9;
// How far from 1 m per m the joint's translation rate may be: rounding of the axis' length.
constexpr double kUnitRateTolerance = 1e-9;

double sample(const std::array<double, 2>& range, int s) {
  return range[0] + (range[1] - range[0]) * s / kRangeSamples;
}

// The child's joint frame M in ground at posture q.
Eigen::Isometry3d joint_frame_in_ground(const OpenSimModel& osim, const OpenSimJoint& j, const OpenSimCoordinateValues& q) {
  return opensim_body_in_ground(osim, j.parent_body, q) * j.parent_offset * opensim_joint_transform(j, q);
}

// The origins and mass centres, in ground, of the bodies that move with the kept joint (not those
// that follow it through a coupler: those are lumped where they are at the reference).
std::vector<Eigen::Vector3d> moving_points(const OpenSimModel& osim, const Reduction& reduction,
                                           const std::vector<std::string>& members, const OpenSimCoordinateValues& q) {
  std::vector<Eigen::Vector3d> out;
  for (const std::string& b : members) {
    if (reduction.coupledToKept(b)) continue;
    const Eigen::Isometry3d X = opensim_body_in_ground(osim, b, q);
    out.push_back(X.translation());
    out.push_back(X * osim.body(b)->mass_center_m);
  }
  return out;
}

// The direction in ground the coordinate translates the joint's child frame along at the
// reference posture, refused unless the joint moves 1 m per m of it.
Eigen::Vector3d translation_axis(const OpenSimModel& osim, const Reduction& reduction, const OpenSimJoint& j,
                                 const std::string& coordinate, const std::string& what) {
  const OpenSimCoordinateValues& q0 = reduction.reference();
  const Eigen::Matrix3d R_GF = (opensim_body_in_ground(osim, j.parent_body, q0) * j.parent_offset).linear();
  const OpenSimJointRate rate = opensim_joint_rate(j, q0, coordinate);
  if (rate.angular.norm() > 0.0) fail(what + " turns with it (a slider only translates)");
  const double speed = rate.linear.norm();
  if (!(speed > 0.0)) fail(what + " does not translate with it");
  if (std::abs(speed - 1.0) > kUnitRateTolerance)
    fail(what + " moves its child " + fixed(speed, 6) +
         " m per m of it (a slider moves 1 m per m: the axis' function must be linear with slope 1 or -1)");
  return R_GF * rate.linear / speed;
}

}  // namespace

ImportedSlider import_slider(const OpenSimModel& osim, const Reduction& reduction, const OpenSimImportOptions& options,
                             const OpenSimJoint& j, const std::string& coordinate,
                             const std::map<std::string, Eigen::Vector3d>& origins, const std::vector<std::string>& members) {
  const std::string what = "kept coordinate '" + coordinate + "': " + j.type + " '" + j.name + "'";
  const OpenSimCoordinate& c = *osim.coordinate(coordinate);
  ImportedSlider out;
  JointDescription& d = out.joint;
  d.type = JointType::Slider;
  d.name = j.name;
  d.coordinate = coordinate;
  d.parent = reduction.owner(j.parent_body);
  d.child = j.child_body;
  d.axis = translation_axis(osim, reduction, j, coordinate, what);
  d.range_rad = c.range;
  if (const auto r = options.ranges.find(coordinate); r != options.ranges.end()) d.range_rad = r->second;
  out.child_origin_in_ground = joint_frame_in_ground(osim, j, reduction.reference()).translation();
  d.location_in_parent_m = out.child_origin_in_ground - origins.at(d.parent);

  // Over the range: the joint's own frame must slide along the axis (else no slider follows it),
  // and every body moving with it is measured the way the pins' are.
  const std::vector<Eigen::Vector3d> at_reference = moving_points(osim, reduction, members, reduction.reference());
  double frame_error_m = 0.0, frame_error_at = 0.0, point_error_m = 0.0;
  for (int s = 0; s <= kRangeSamples; ++s) {
    const double q = sample(d.range_rad, s);
    const OpenSimCoordinateValues moved = reduction.moved(coordinate, q);
    const double e = (joint_frame_in_ground(osim, j, moved).translation() - (out.child_origin_in_ground + q * d.axis)).norm();
    if (e > frame_error_m) frame_error_m = e, frame_error_at = q;
    const std::vector<Eigen::Vector3d> truth = moving_points(osim, reduction, members, moved);
    for (std::size_t i = 0; i < truth.size(); ++i) point_error_m = std::max(point_error_m, (truth[i] - (at_reference[i] + q * d.axis)).norm());
  }
  if (frame_error_m > kExactSliderTolerance_m)
    fail(what + " does not move its child along one direction at 1 m per m over the range: " + fixed(frame_error_m * 1e3, 3) +
         " mm off a straight slide at " + shown(c, frame_error_at) + " (a slider cannot follow it)");
  out.provenance = {{"coordinate", coordinate},
                    {"opensim_joint_type", j.type},
                    {"exact", point_error_m <= kExactSliderTolerance_m},
                    {"joint_point_error_m", point_error_m},
                    {"axis_in_ground", {d.axis[0], d.axis[1], d.axis[2]}},
                    {"range_m", {d.range_rad[0], d.range_rad[1]}},
                    {"approximation",
                     "a slider along the direction the coordinate translates its joint at the reference posture: exact for a "
                     "joint that is that one translation (sliders.*.exact, sliders.*.joint_point_error_m)"}};
  return out;
}

Eigen::Vector3d placed_by_joint(const JointDescription& d, double q, const Eigen::Vector3d& joint_origin,
                                const Eigen::Vector3d& point) {
  if (d.isSlider()) return point + q * d.axis;
  return joint_origin + Eigen::AngleAxisd(q, d.axis) * (point - joint_origin);
}

}  // namespace flatsos::plugin::opensim_import
