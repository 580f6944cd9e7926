// Moment arms and lengthening speed of an evaluated path, as OpenSim computes them: every node,
// tangent points included, moves with its body (PathWrapPoint, MomentArmSolver), a moving path
// point also along its functions; the moment arm sums the unit segment directions' work over
// segments joining different bodies (GeometryPath::produceForces), the speed over all segments
// (Point::calcSpeedBetween). Coincident points (OpenSim: NaN) add nothing here.
// Segment directions use the ground locations OpenSim's caches hold, the points' motion their
// current places (as OpenSim applies forces at getLocation and maps them by its Jacobian).

#include <algorithm>

#include "path_workspace.hpp"

namespace flatsos::plugin {

double GeometryPathEvaluator::rate_along_path(const OpenSimCoordinateValues& q, Workspace& w, const std::string& coordinate,
                                              bool all_segments) const {
  // Each body's angular velocity and origin velocity (in ground) per unit rate of the coordinate.
  auto pose_of = [&](const std::string& body) -> const Eigen::Isometry3d& {
    return w.poses[std::find(bodies_.begin(), bodies_.end(), body) - bodies_.begin()];
  };
  std::vector<Eigen::Vector3d> angular(bodies_.size(), Eigen::Vector3d::Zero()), linear(bodies_.size(), Eigen::Vector3d::Zero());
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    const Eigen::Vector3d origin = w.poses[b].translation();
    for (const OpenSimJoint* joint : chains_[b]) {
      const OpenSimJointRate rate = opensim_joint_rate(*joint, q, coordinate);
      if (rate.angular.isZero(0.0) && rate.linear.isZero(0.0)) continue;
      const Eigen::Matrix3d R_GF = pose_of(joint->parent_body).linear() * joint->parent_offset.linear();
      const Eigen::Vector3d joint_origin = (pose_of(joint->child_body) * joint->child_offset).translation();
      const Eigen::Vector3d omega = R_GF * rate.angular;
      angular[b] += omega;
      linear[b] += R_GF * rate.linear + omega.cross(origin - joint_origin);
    }
  }
  auto node_rate = [&](const Node& n) {
    Eigen::Vector3d v = linear[n.body] + angular[n.body].cross(n.ground - w.poses[n.body].translation());
    if (n.point >= 0 && path_.points[n.point].kind == OpenSimPathPointKind::Moving && path_.points[n.point].coordinate == coordinate)
      v += w.poses[n.body].linear() * n.moving_rate_local;
    return v;
  };
  double rate = 0.0;
  for (std::size_t i = 1; i < w.path.size(); ++i) {
    const Node& a = w.path[i - 1];
    const Node& b = w.path[i];
    if (!all_segments && a.body == b.body) continue;
    // Directions from the ground locations OpenSim has cached (see Workspace::ground_as_seen).
    const Eigen::Vector3d d = w.ground_as_seen(b) - w.ground_as_seen(a);
    const double length = d.norm();
    if (!(length > 0.0)) continue;
    rate += d.dot(node_rate(b) - node_rate(a)) / length;
  }
  return rate;
}

double GeometryPathEvaluator::momentArm(const OpenSimCoordinateValues& q, const std::string& coordinate) const {
  if (!model_.coordinate(coordinate)) throw OpenSimModelError(path_.muscle + ": the model has no coordinate '" + coordinate + "'");
  Workspace w;
  compute(q, w, false);
  double dL_dq = rate_along_path(q, w, coordinate, false);
  // Coordinates a coupler drives from this one move with it (OpenSim's coupling vector).
  for (const OpenSimCoupler& c : model_.couplers)
    if (c.independent == coordinate)
      dL_dq += c.scale * c.function.derivative(value_of(q, coordinate)) * rate_along_path(q, w, c.dependent, false);
  return -dL_dq;
}

double GeometryPathEvaluator::lengtheningSpeed(const OpenSimCoordinateValues& q, const OpenSimCoordinateValues& qdot) const {
  Workspace w;
  compute(q, w, false);
  double speed = 0.0;
  for (const auto& [coordinate, rate] : qdot)
    if (rate != 0.0) speed += rate * rate_along_path(q, w, coordinate, true);
  return speed;
}

double GeometryPathEvaluator::lengthWithPathHeld(const OpenSimCoordinateValues& q_path, const OpenSimCoordinateValues& q) const {
  Workspace w;
  compute(q_path, w, false);
  std::vector<Eigen::Isometry3d> poses;
  body_poses(q, poses);
  auto place = [&](const Node& n) {
    const Eigen::Vector3d local = n.point >= 0 ? point_location(n.point, q, nullptr) : n.local;
    return Eigen::Vector3d(poses[n.body] * local);
  };
  double length = 0.0;
  for (std::size_t i = 1; i < w.path.size(); ++i) {
    const Node& a = w.path[i - 1];
    const Node& b = w.path[i];
    length += a.object >= 0 && a.object == b.object ? b.surface_length : (place(b) - place(a)).norm();
  }
  return length;
}

}  // namespace flatsos::plugin
