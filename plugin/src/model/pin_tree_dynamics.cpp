#include "flatsos/plugin/model/pin_tree_dynamics.hpp"

#include <map>
#include <stdexcept>
#include <string>

#include "flatsos/plugin/model/dual_number.hpp"
#include "flatsos/plugin/model/joint_limit.hpp"

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
    j.slider = jd.isSlider();
    j.location_in_parent_m = jd.location_in_parent_m;
    j.axis = jd.axis.normalized();
    j.axis_cross << 0.0, -j.axis[2], j.axis[1], j.axis[2], 0.0, -j.axis[0], -j.axis[1], j.axis[0], 0.0;
    j.axis_cross_squared = j.axis_cross * j.axis_cross;
    const BodyDescription& b = *bodies.at(jd.child);
    j.mass_kg = b.mass_kg;
    j.mass_center_m = b.mass_center_m;
    j.inertia_about_com_kg_m2 = inertia_matrix(b);
    j.limit = jd.limit;
    j.range_rad = jd.range_rad;
    has_limits_ = has_limits_ || jd.limit.enabled();
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
  inverseDynamicsOf<double>(scratch, q.data(), qd.data(), qdd.data(), tau.data());
}

void PinTreeDynamics::rigidBodyInverseDynamics(Scratch& scratch, const Eigen::Ref<const Eigen::VectorXd>& q,
                                               const Eigen::Ref<const Eigen::VectorXd>& qd,
                                               const Eigen::Ref<const Eigen::VectorXd>& qdd,
                                               Eigen::Ref<Eigen::VectorXd> tau) const {
  rigidBodyTorquesOf<double>(scratch, q.data(), qd.data(), qdd.data(), tau.data());
}

void PinTreeDynamics::jointLimitTorques(const Eigen::Ref<const Eigen::VectorXd>& q,
                                        const Eigen::Ref<const Eigen::VectorXd>& qd,
                                        Eigen::Ref<Eigen::VectorXd> tau) const {
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    const Joint& j = joints_[i];
    const auto k = static_cast<Eigen::Index>(i);
    tau[k] = joint_limit_torque(j.limit, j.range_rad[0], j.range_rad[1], q[k], qd[k]);
  }
}

void PinTreeDynamics::jointLimitTorqueJet(const Eigen::Ref<const Eigen::MatrixXd>& q_jet,
                                          Eigen::Ref<Eigen::MatrixXd> out) const {
  // Time jets along the motion, as in torque_jet_of below; q''' enters through the damper's second
  // derivative. Jet columns not given are 0.
  using H = TimeJet<double>;
  auto column = [&](Eigen::Index i, Eigen::Index order) { return order < q_jet.cols() ? q_jet(i, order) : 0.0; };
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    const Joint& j = joints_[i];
    const auto k = static_cast<Eigen::Index>(i);
    if (!j.limit.enabled()) {
      out.row(k).setZero();
      continue;
    }
    const H q(column(k, 0), column(k, 1), column(k, 2));
    const H qd(column(k, 1), column(k, 2), column(k, 3));
    const H t = joint_limit_torque(j.limit, j.range_rad[0], j.range_rad[1], q, qd);
    out(k, 0) = t.value;
    out(k, 1) = t.rate;
    out(k, 2) = t.acceleration;
  }
}

template <class S>
void PinTreeDynamics::inverseDynamicsOf(ScratchOf<S>& scratch, const S* q, const S* qd, const S* qdd, S* tau) const {
  rigidBodyTorquesOf(scratch, q, qd, qdd, tau);
  if (!has_limits_) return;
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    const Joint& j = joints_[i];
    tau[i] -= joint_limit_torque(j.limit, j.range_rad[0], j.range_rad[1], q[i], qd[i]);
  }
}

namespace {
// Products of S-valued vectors and matrices with the model's constants (axes, offsets, mass
// centres, inertias): each such product scales an entry (scaled, dual_number.hpp) instead of
// multiplying two jets, and the constants' zeros (axes and offsets along a frame axis, diagonal
// inertias) are skipped. The dual passes of the free path's torque-jet gradient spend their time
// here.
template <class S>
using Vec3 = Eigen::Matrix<S, 3, 1>;
template <class S>
using Mat3 = Eigen::Matrix<S, 3, 3>;

// A v for a constant v.
template <class S>
Vec3<S> times_constant(const Mat3<S>& A, const Eigen::Vector3d& v) {
  Vec3<S> out = Vec3<S>::Zero();
  for (int k = 0; k < 3; ++k)
    if (v[k] != 0.0)
      for (int i = 0; i < 3; ++i) out[i] += scaled(A(i, k), v[k]);
  return out;
}

// A B for a constant B.
template <class S>
Mat3<S> times_constant(const Mat3<S>& A, const Eigen::Matrix3d& B) {
  Mat3<S> out = Mat3<S>::Zero();
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      if (B(k, j) != 0.0)
        for (int i = 0; i < 3; ++i) out(i, j) += scaled(A(i, k), B(k, j));
  return out;
}

// B v for a constant B.
template <class S>
Vec3<S> constant_times(const Eigen::Matrix3d& B, const Vec3<S>& v) {
  Vec3<S> out = Vec3<S>::Zero();
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k)
      if (B(i, k) != 0.0) out[i] += scaled(v[k], B(i, k));
  return out;
}

// x v for a constant v.
template <class S>
Vec3<S> along_constant(const S& x, const Eigen::Vector3d& v) {
  Vec3<S> out = Vec3<S>::Zero();
  for (int i = 0; i < 3; ++i)
    if (v[i] != 0.0) out[i] = scaled(x, v[i]);
  return out;
}
}  // namespace

// A pin: the child turns by q about the axis fixed in the parent.
template <class S>
void PinTreeDynamics::pinKinematicsOf(const Joint& j, const BodyOf<S>* parent, const S& q, const S& qd, const S& qdd,
                                      BodyOf<S>& b) {
  using Vec = Vec3<S>;
  using std::cos;
  using std::sin;
  // Rodrigues: the rotation by q about the unit axis, R = I + sin q K + (1 - cos q) K^2, turned
  // by the parent's rotation P: P R = P + sin q (P K) + (1 - cos q) (P K^2).
  const S sin_q = sin(q), one_minus_cos_q = S(1.0) - cos(q);
  if (!parent) {  // on the ground: the parent's frame is the ground's, at rest
    b.origin_m = j.location_in_parent_m.cast<S>();
    b.axis = j.axis.cast<S>();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        S entry(r == c ? 1.0 : 0.0);
        if (j.axis_cross(r, c) != 0.0) entry += scaled(sin_q, j.axis_cross(r, c));
        if (j.axis_cross_squared(r, c) != 0.0) entry += scaled(one_minus_cos_q, j.axis_cross_squared(r, c));
        b.rotation(r, c) = entry;
      }
    b.origin_acceleration = Vec::Zero();
    b.angular_velocity = along_constant(qd, j.axis);
    b.angular_acceleration = along_constant(qdd, j.axis);
    return;
  }
  const BodyOf<S>& p = *parent;
  const Vec r = times_constant(p.rotation, j.location_in_parent_m);  // parent origin -> joint
  b.axis = times_constant(p.rotation, j.axis);
  b.rotation = p.rotation + sin_q * times_constant(p.rotation, j.axis_cross) +
               one_minus_cos_q * times_constant(p.rotation, j.axis_cross_squared);
  b.origin_m = p.origin_m + r;
  const Vec& w = p.angular_velocity;
  b.origin_acceleration = p.origin_acceleration + p.angular_acceleration.cross(r) + w.cross(w.cross(r));
  b.angular_velocity = w + b.axis * qd;
  // The axis is fixed in the parent, so it turns with the parent's angular velocity.
  b.angular_acceleration = p.angular_acceleration + b.axis * qdd + w.cross(b.axis) * qd;
}

// A slider: the child keeps the parent's orientation and its origin moves by q along the axis
// fixed in the parent, r = P (location + q axis), so its acceleration adds to the parent's
// alpha x r + w x (w x r) the Coriolis term 2 w x (P axis qd) and P axis qdd.
template <class S>
void PinTreeDynamics::sliderKinematicsOf(const Joint& j, const BodyOf<S>* parent, const S& q, const S& qd, const S& qdd,
                                         BodyOf<S>& b) {
  using Vec = Vec3<S>;
  if (!parent) {
    b.axis = j.axis.cast<S>();
    b.rotation = Mat3<S>::Identity();
    b.origin_m = j.location_in_parent_m.cast<S>() + along_constant(q, j.axis);
    b.angular_velocity = Vec::Zero();
    b.angular_acceleration = Vec::Zero();
    b.origin_acceleration = along_constant(qdd, j.axis);
    return;
  }
  const BodyOf<S>& p = *parent;
  b.axis = times_constant(p.rotation, j.axis);
  const Vec r = times_constant(p.rotation, j.location_in_parent_m) + b.axis * q;  // parent origin -> child origin
  b.rotation = p.rotation;
  b.origin_m = p.origin_m + r;
  const Vec& w = p.angular_velocity;
  b.angular_velocity = w;
  b.angular_acceleration = p.angular_acceleration;
  const Vec sliding = b.axis * qd;
  b.origin_acceleration = p.origin_acceleration + p.angular_acceleration.cross(r) + w.cross(w.cross(r)) +
                          S(2.0) * w.cross(sliding) + b.axis * qdd;
}

template <class S>
void PinTreeDynamics::rigidBodyTorquesOf(ScratchOf<S>& scratch, const S* q, const S* qd, const S* qdd, S* tau) const {
  using Vec = Vec3<S>;
  const int n = numJoints();
  scratch.bodies.resize(joints_.size());  // no allocation once sized
  // Outward: kinematics of each body from its parent's (parents come first), and the body's own
  // inertial and gravity load.
  for (int i = 0; i < n; ++i) {
    const Joint& j = joints_[static_cast<std::size_t>(i)];
    auto& b = scratch.bodies[static_cast<std::size_t>(i)];
    const BodyOf<S>* parent = j.parent < 0 ? nullptr : &scratch.bodies[static_cast<std::size_t>(j.parent)];
    if (j.slider)
      sliderKinematicsOf<S>(j, parent, q[i], qd[i], qdd[i], b);
    else
      pinKinematicsOf<S>(j, parent, q[i], qd[i], qdd[i], b);
    const Vec& wb = b.angular_velocity;
    const Vec c = times_constant(b.rotation, j.mass_center_m);  // origin -> mass center
    const Vec com_acceleration = b.origin_acceleration + b.angular_acceleration.cross(c) + wb.cross(wb.cross(c));
    // The inertia about the mass center acts in the body's frame: R I R^T v = R (I (R^T v)).
    const auto inertia_times = [&](const Vec& v) {
      return Vec(b.rotation * constant_times(j.inertia_about_com_kg_m2, Vec(b.rotation.transpose() * v)));
    };
    Vec load = com_acceleration;
    for (int k = 0; k < 3; ++k) load[k] -= S(gravity_m_per_s2_[k]);
    for (int k = 0; k < 3; ++k) b.force_N[k] = scaled(load[k], j.mass_kg);
    b.moment_N_m = inertia_times(b.angular_acceleration) + wb.cross(inertia_times(wb)) + c.cross(b.force_N);
  }
  // Inward: children add their loads to their parents (children come after their parents). A
  // pin's torque is the moment's component along its axis, a slider's force the force's.
  for (int i = n - 1; i >= 0; --i) {
    const Joint& j = joints_[static_cast<std::size_t>(i)];
    const auto& b = scratch.bodies[static_cast<std::size_t>(i)];
    tau[i] = j.slider ? b.axis.dot(b.force_N) : b.axis.dot(b.moment_N_m);
    if (j.parent >= 0) {
      auto& p = scratch.bodies[static_cast<std::size_t>(j.parent)];
      p.force_N += b.force_N;
      p.moment_N_m += b.moment_N_m + (b.origin_m - p.origin_m).cross(b.force_N);
    }
  }
}

// Every scalar type the tree is evaluated in: plain, dual numbers (Jacobians, Hessians) and time
// jets of them (torque jets, their gradients and Hessians: pin_tree_derivatives.cpp).
#define FLATSOS_INSTANTIATE_INVERSE_DYNAMICS(S) \
  template void PinTreeDynamics::inverseDynamicsOf<S>(ScratchOf<S>&, const S*, const S*, const S*, S*) const;
FLATSOS_INSTANTIATE_INVERSE_DYNAMICS(double)
FLATSOS_INSTANTIATE_INVERSE_DYNAMICS(Dual<double>)
FLATSOS_INSTANTIATE_INVERSE_DYNAMICS(Dual<Dual<double>>)
FLATSOS_INSTANTIATE_INVERSE_DYNAMICS(TimeJet<double>)
FLATSOS_INSTANTIATE_INVERSE_DYNAMICS(TimeJet<Dual<double>>)
FLATSOS_INSTANTIATE_INVERSE_DYNAMICS(TimeJet<Dual<Dual<double>>>)
#undef FLATSOS_INSTANTIATE_INVERSE_DYNAMICS

}  // namespace flatsos::plugin
