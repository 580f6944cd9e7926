#include "flatsos/plugin/model/pin_tree_dynamics.hpp"

#include <map>
#include <string>

namespace flatsos::plugin {

namespace {
// Inertia matrix about the mass center from the description's moments (Ixx, Iyy, Izz) and
// products (Ixy, Ixz, Iyz), the off-diagonal entries as Simbody's Inertia takes them.
Eigen::Matrix3d inertia_matrix(const BodyDescription& b) {
  const Eigen::Vector3d& d = b.principal_inertia_kg_m2;
  const Eigen::Vector3d& p = b.product_inertia_kg_m2;
  Eigen::Matrix3d I;
  I << d[0], p[0], p[1],
       p[0], d[1], p[2],
       p[1], p[2], d[2];
  return I;
}
}  // namespace

PinTreeDynamics::PinTreeDynamics(const ModelDescription& description)
    : gravity_m_per_s2_(description.gravity_m_per_s2) {
  std::map<std::string, const BodyDescription*> bodies;
  for (const auto& b : description.bodies) bodies[b.name] = &b;
  std::map<std::string, int> joint_of_body;  // the joint whose child a body is
  for (const auto& jd : description.joints) {
    Joint j;
    j.parent = jd.parent == "ground" ? -1 : joint_of_body.at(jd.parent);
    j.location_in_parent_m = jd.location_in_parent_m;
    j.axis = jd.axis.normalized();
    const BodyDescription& b = *bodies.at(jd.child);
    j.mass_kg = b.mass_kg;
    j.mass_center_m = b.mass_center_m;
    j.inertia_about_com_kg_m2 = inertia_matrix(b);
    joint_of_body[jd.child] = static_cast<int>(joints_.size());
    joints_.push_back(j);
  }
}

PinTreeDynamics::Scratch PinTreeDynamics::makeScratch() const {
  Scratch s;
  s.bodies.resize(joints_.size());
  return s;
}

void PinTreeDynamics::inverseDynamics(Scratch& scratch, const Eigen::Ref<const Eigen::VectorXd>& q,
                                      const Eigen::Ref<const Eigen::VectorXd>& qd,
                                      const Eigen::Ref<const Eigen::VectorXd>& qdd,
                                      Eigen::Ref<Eigen::VectorXd> tau) const {
  const int n = numJoints();
  // Outward: kinematics of each body from its parent's (parents come first), and the body's own
  // inertial and gravity load.
  for (int i = 0; i < n; ++i) {
    const Joint& j = joints_[static_cast<std::size_t>(i)];
    Scratch::Body& b = scratch.bodies[static_cast<std::size_t>(i)];
    Eigen::Matrix3d parent_rotation = Eigen::Matrix3d::Identity();
    Eigen::Vector3d parent_origin = Eigen::Vector3d::Zero(), w = Eigen::Vector3d::Zero(),
                    wd = Eigen::Vector3d::Zero(), a = Eigen::Vector3d::Zero();
    if (j.parent >= 0) {
      const Scratch::Body& p = scratch.bodies[static_cast<std::size_t>(j.parent)];
      parent_rotation = p.rotation;
      parent_origin = p.origin_m;
      w = p.angular_velocity;
      wd = p.angular_acceleration;
      a = p.origin_acceleration;
    }
    const Eigen::Vector3d r = parent_rotation * j.location_in_parent_m;  // parent origin -> joint
    b.axis = parent_rotation * j.axis;
    b.rotation = parent_rotation * Eigen::AngleAxisd(q[i], j.axis).toRotationMatrix();
    b.origin_m = parent_origin + r;
    b.origin_acceleration = a + wd.cross(r) + w.cross(w.cross(r));
    b.angular_velocity = w + b.axis * qd[i];
    // The axis is fixed in the parent, so it turns with the parent's angular velocity.
    b.angular_acceleration = wd + b.axis * qdd[i] + w.cross(b.axis) * qd[i];

    const Eigen::Vector3d& wb = b.angular_velocity;
    const Eigen::Vector3d c = b.rotation * j.mass_center_m;  // origin -> mass center
    const Eigen::Vector3d com_acceleration =
        b.origin_acceleration + b.angular_acceleration.cross(c) + wb.cross(wb.cross(c));
    const Eigen::Matrix3d inertia = b.rotation * j.inertia_about_com_kg_m2 * b.rotation.transpose();
    b.force_N = j.mass_kg * (com_acceleration - gravity_m_per_s2_);
    b.moment_N_m = inertia * b.angular_acceleration + wb.cross(inertia * wb) + c.cross(b.force_N);
  }
  // Inward: children add their loads to their parents (children come after their parents).
  for (int i = n - 1; i >= 0; --i) {
    const Joint& j = joints_[static_cast<std::size_t>(i)];
    const Scratch::Body& b = scratch.bodies[static_cast<std::size_t>(i)];
    tau[i] = b.axis.dot(b.moment_N_m);
    if (j.parent >= 0) {
      Scratch::Body& p = scratch.bodies[static_cast<std::size_t>(j.parent)];
      p.force_N += b.force_N;
      p.moment_N_m += b.moment_N_m + (b.origin_m - p.origin_m).cross(b.force_N);
    }
  }
}

}  // namespace flatsos::plugin
