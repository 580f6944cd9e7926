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

template <class S>
void PinTreeDynamics::rigidBodyTorquesOf(ScratchOf<S>& scratch, const S* q, const S* qd, const S* qdd, S* tau) const {
  using Vec = Vec3<S>;
  using std::cos;
  using std::sin;
  const int n = numJoints();
  scratch.bodies.resize(joints_.size());  // no allocation once sized
  // Outward: kinematics of each body from its parent's (parents come first), and the body's own
  // inertial and gravity load.
  for (int i = 0; i < n; ++i) {
    const Joint& j = joints_[static_cast<std::size_t>(i)];
    auto& b = scratch.bodies[static_cast<std::size_t>(i)];
    // Rodrigues: the rotation by q about the unit axis, R = I + sin q K + (1 - cos q) K^2, turned
    // by the parent's rotation P: P R = P + sin q (P K) + (1 - cos q) (P K^2).
    const S sin_q = sin(q[i]), one_minus_cos_q = S(1.0) - cos(q[i]);
    if (j.parent < 0) {  // on the ground: the parent's frame is the ground's, at rest
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
      b.angular_velocity = along_constant(qd[i], j.axis);
      b.angular_acceleration = along_constant(qdd[i], j.axis);
    } else {
      const auto& p = scratch.bodies[static_cast<std::size_t>(j.parent)];
      const Vec r = times_constant(p.rotation, j.location_in_parent_m);  // parent origin -> joint
      b.axis = times_constant(p.rotation, j.axis);
      b.rotation = p.rotation + sin_q * times_constant(p.rotation, j.axis_cross) +
                   one_minus_cos_q * times_constant(p.rotation, j.axis_cross_squared);
      b.origin_m = p.origin_m + r;
      const Vec& w = p.angular_velocity;
      b.origin_acceleration = p.origin_acceleration + p.angular_acceleration.cross(r) + w.cross(w.cross(r));
      b.angular_velocity = w + b.axis * qd[i];
      // The axis is fixed in the parent, so it turns with the parent's angular velocity.
      b.angular_acceleration = p.angular_acceleration + b.axis * qdd[i] + w.cross(b.axis) * qd[i];
    }
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
  // Inward: children add their loads to their parents (children come after their parents).
  for (int i = n - 1; i >= 0; --i) {
    const Joint& j = joints_[static_cast<std::size_t>(i)];
    const auto& b = scratch.bodies[static_cast<std::size_t>(i)];
    tau[i] = b.axis.dot(b.moment_N_m);
    if (j.parent >= 0) {
      auto& p = scratch.bodies[static_cast<std::size_t>(j.parent)];
      p.force_N += b.force_N;
      p.moment_N_m += b.moment_N_m + (b.origin_m - p.origin_m).cross(b.force_N);
    }
  }
}

namespace {

// The buffers of torque_jet_from_seeds, kept across the passes of one gradient or Hessian.
template <class S>
struct TorqueJetBuffers {
  std::vector<TimeJet<S>> q, qd, qdd, tau;
  PinTreeDynamics::ScratchOf<TimeJet<S>> scratch;
};

// tau along a motion as a time jet: each of q, qd, qdd is (x, x', x'') read from the jet, so tau
// comes out with d/dt and d2/dt2 of tau(t) = ID(q(t), qd(t), qdd(t)). `seed(joint, block)` gives
// that jet for q (block 0), qd (1) or qdd (2) of a joint.
template <class S, class SeedAt>
void torque_jet_from_seeds(const PinTreeDynamics& tree, const SeedAt& seed, std::vector<S>& tau_out,
                           TorqueJetBuffers<S>& buffers) {
  using H = TimeJet<S>;
  const int n = tree.numJoints();
  const auto size = static_cast<std::size_t>(n);
  buffers.q.resize(size), buffers.qd.resize(size), buffers.qdd.resize(size), buffers.tau.resize(size);
  for (int i = 0; i < n; ++i) {
    buffers.q[static_cast<std::size_t>(i)] = seed(i, 0);
    buffers.qd[static_cast<std::size_t>(i)] = seed(i, 1);
    buffers.qdd[static_cast<std::size_t>(i)] = seed(i, 2);
  }
  tree.inverseDynamicsOf<H>(buffers.scratch, buffers.q.data(), buffers.qd.data(), buffers.qdd.data(), buffers.tau.data());
  tau_out.resize(static_cast<std::size_t>(3 * n));
  for (int i = 0; i < n; ++i) {
    const H& t = buffers.tau[static_cast<std::size_t>(i)];
    tau_out[static_cast<std::size_t>(3 * i)] = t.value;
    tau_out[static_cast<std::size_t>(3 * i + 1)] = t.rate;
    tau_out[static_cast<std::size_t>(3 * i + 2)] = t.acceleration;
  }
}

// The same with every seed read from the jet: jet(joint, order), orders 0..4.
template <class S, class JetAt>
void torque_jet_of(const PinTreeDynamics& tree, const JetAt& jet, std::vector<S>& tau_out, TorqueJetBuffers<S>& buffers) {
  torque_jet_from_seeds<S>(
      tree,
      [&](int joint, int block) {
        return TimeJet<S>(jet(joint, block), jet(joint, block + 1), jet(joint, block + 2));
      },
      tau_out, buffers);
}

void require_jet(const PinTreeDynamics& tree, const Eigen::Ref<const Eigen::MatrixXd>& q_jet) {
  if (q_jet.rows() != tree.numJoints() || q_jet.cols() < 5)
    throw std::invalid_argument("torque jet: the joint jet must be " + std::to_string(tree.numJoints()) +
                                " x 5 (q and four derivatives), not " + std::to_string(q_jet.rows()) + " x " +
                                std::to_string(q_jet.cols()));
}

}  // namespace

Eigen::MatrixXd PinTreeDynamics::torqueJet(const Eigen::Ref<const Eigen::MatrixXd>& q_jet) const {
  require_jet(*this, q_jet);
  std::vector<double> tau;
  TorqueJetBuffers<double> buffers;
  torque_jet_of<double>(*this, [&](int r, int l) { return q_jet(r, l); }, tau, buffers);
  Eigen::MatrixXd out(numJoints(), 3);
  for (int i = 0; i < numJoints(); ++i)
    for (int k = 0; k < 3; ++k) out(i, k) = tau[static_cast<std::size_t>(3 * i + k)];
  return out;
}

Eigen::MatrixXd PinTreeDynamics::torqueJet(const Eigen::Ref<const Eigen::MatrixXd>& q_jet,
                                           Eigen::MatrixXd& gradient) const {
  require_jet(*this, q_jet);
  const int n = numJoints();
  gradient.setZero(3 * n, 5 * n);
  Eigen::MatrixXd out(n, 3);
  std::vector<Dual<double>> tau;
  TorqueJetBuffers<Dual<double>> buffers;
  // tau(t) = ID(x(t)) with x = (q, qd, qdd), so d tau^(k) / d x^(j) = binom(k, j) A^(k-j),
  // where A(t) = dID/dx along the motion (the Jacobian of a Taylor expansion is lower
  // block-Toeplitz in the Jacobian's own expansion). One pass per entry of x (3N), with a third
  // infinitesimal constant in time on that entry, gives A e and its first two time derivatives;
  // q^(l) is block l - j of x^(j). One pass per entry of the jet took 5N.
  constexpr double kBinomial[3][3] = {{1.0, 0.0, 0.0}, {1.0, 1.0, 0.0}, {1.0, 2.0, 1.0}};
  using D = Dual<double>;
  for (int r = 0; r < n; ++r)
    for (int b = 0; b < 3; ++b) {
      torque_jet_from_seeds<D>(
          *this,
          [&](int joint, int block) {
            const double x = q_jet(joint, block), x1 = q_jet(joint, block + 1), x2 = q_jet(joint, block + 2);
            return TimeJet<D>(D(x, joint == r && block == b ? 1.0 : 0.0), D(x1), D(x2));
          },
          tau, buffers);
      for (int i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k)
          for (int j = 0; j <= k; ++j)
            gradient(3 * i + k, 5 * r + b + j) +=
                kBinomial[k][j] * tau[static_cast<std::size_t>(3 * i + k - j)].derivative;
    }
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) out(i, k) = tau[static_cast<std::size_t>(3 * i + k)].value;
  return out;
}

Eigen::MatrixXd PinTreeDynamics::torqueJetHessian(const Eigen::Ref<const Eigen::MatrixXd>& q_jet,
                                                  const Eigen::Ref<const Eigen::MatrixXd>& weights) const {
  require_jet(*this, q_jet);
  const int n = numJoints();
  if (weights.rows() != n || weights.cols() != 3)
    throw std::invalid_argument("torque jet Hessian: the weights must be " + std::to_string(n) + " x 3, not " +
                                std::to_string(weights.rows()) + " x " + std::to_string(weights.cols()));
  using S = Dual<Dual<double>>;
  std::vector<S> tau;
  TorqueJetBuffers<S> buffers;
  Eigen::MatrixXd hessian = Eigen::MatrixXd::Zero(5 * n, 5 * n);
  for (int a = 0; a < 5 * n; ++a)
    for (int b = 0; b <= a; ++b) {
      const int la = std::max(a % 5, b % 5), lb = std::min(a % 5, b % 5);
      if ((la == 4 && lb >= 1) || (la == 3 && lb >= 2)) continue;  // structurally zero (above)
      // Entry a carries e3, entry b e4: the e3 e4 coefficient of each tau^(k) is its d2 / da db.
      torque_jet_of<S>(
          *this,
          [&](int joint, int order) {
            const int entry = 5 * joint + order;
            return S(Dual<double>(q_jet(joint, order), entry == b ? 1.0 : 0.0), Dual<double>(entry == a ? 1.0 : 0.0, 0.0));
          },
          tau, buffers);
      double sum = 0.0;
      for (int i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) sum += weights(i, k) * tau[static_cast<std::size_t>(3 * i + k)].derivative.derivative;
      hessian(a, b) = hessian(b, a) = sum;
    }
  return hessian;
}

namespace {
void require_state(const PinTreeDynamics& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                   const Eigen::Ref<const Eigen::VectorXd>& qd, const Eigen::Ref<const Eigen::VectorXd>& qdd) {
  const int n = tree.numJoints();
  if (q.size() != n || qd.size() != n || qdd.size() != n)
    throw std::invalid_argument("inverse dynamics derivatives: q, qd and qdd must have " + std::to_string(n) +
                                " entries, not " + std::to_string(q.size()) + ", " + std::to_string(qd.size()) +
                                " and " + std::to_string(qdd.size()));
}
// x = (q, qd, qdd) stacked by kind.
double stacked(const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& qd,
               const Eigen::Ref<const Eigen::VectorXd>& qdd, int k) {
  const int n = static_cast<int>(q.size());
  return k < n ? q[k] : k < 2 * n ? qd[k - n] : qdd[k - 2 * n];
}
}  // namespace

Eigen::VectorXd PinTreeDynamics::inverseDynamicsJacobian(const Eigen::Ref<const Eigen::VectorXd>& q,
                                                         const Eigen::Ref<const Eigen::VectorXd>& qd,
                                                         const Eigen::Ref<const Eigen::VectorXd>& qdd,
                                                         Eigen::MatrixXd& jacobian) const {
  require_state(*this, q, qd, qdd);
  using D = Dual<double>;
  const int n = numJoints();
  std::vector<D> x(static_cast<std::size_t>(3 * n)), tau(static_cast<std::size_t>(n));
  ScratchOf<D> scratch;
  jacobian.resize(n, 3 * n);
  Eigen::VectorXd out(n);
  for (int c = 0; c < 3 * n; ++c) {  // one pass per entry of x, its infinitesimal on that entry
    for (int k = 0; k < 3 * n; ++k) x[static_cast<std::size_t>(k)] = D(stacked(q, qd, qdd, k), k == c ? 1.0 : 0.0);
    inverseDynamicsOf<D>(scratch, x.data(), x.data() + n, x.data() + 2 * n, tau.data());
    for (int i = 0; i < n; ++i) jacobian(i, c) = tau[static_cast<std::size_t>(i)].derivative;
  }
  for (int i = 0; i < n; ++i) out[i] = tau[static_cast<std::size_t>(i)].value;
  return out;
}

Eigen::MatrixXd PinTreeDynamics::inverseDynamicsHessian(const Eigen::Ref<const Eigen::VectorXd>& q,
                                                        const Eigen::Ref<const Eigen::VectorXd>& qd,
                                                        const Eigen::Ref<const Eigen::VectorXd>& qdd,
                                                        const Eigen::Ref<const Eigen::VectorXd>& w) const {
  require_state(*this, q, qd, qdd);
  const int n = numJoints();
  if (w.size() != n)
    throw std::invalid_argument("inverse dynamics Hessian: the weights must have " + std::to_string(n) + " entries");
  using H = Dual<Dual<double>>;
  std::vector<H> x(static_cast<std::size_t>(3 * n)), tau(static_cast<std::size_t>(n));
  ScratchOf<H> scratch;
  Eigen::MatrixXd hessian = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (int a = 0; a < 3 * n; ++a)
    for (int b = 0; b <= a; ++b) {
      if (a >= 2 * n && b >= n) continue;  // qdd-qd and qdd-qdd: tau is linear in qdd
      // x + e1 delta_a + e2 delta_b: the e1 e2 coefficient of tau is d2 tau / dx_a dx_b.
      for (int k = 0; k < 3 * n; ++k)
        x[static_cast<std::size_t>(k)] = H(Dual<double>(stacked(q, qd, qdd, k), k == a ? 1.0 : 0.0),
                                           Dual<double>(k == b ? 1.0 : 0.0, 0.0));
      inverseDynamicsOf<H>(scratch, x.data(), x.data() + n, x.data() + 2 * n, tau.data());
      double sum = 0.0;
      for (int i = 0; i < n; ++i) sum += w[i] * tau[static_cast<std::size_t>(i)].derivative.derivative;
      hessian(a, b) = hessian(b, a) = sum;
    }
  return hessian;
}

template void PinTreeDynamics::inverseDynamicsOf<double>(ScratchOf<double>&, const double*, const double*, const double*,
                                                         double*) const;
template void PinTreeDynamics::inverseDynamicsOf<Dual<double>>(ScratchOf<Dual<double>>&, const Dual<double>*,
                                                               const Dual<double>*, const Dual<double>*,
                                                               Dual<double>*) const;
template void PinTreeDynamics::inverseDynamicsOf<Dual<Dual<double>>>(ScratchOf<Dual<Dual<double>>>&,
                                                                     const Dual<Dual<double>>*, const Dual<Dual<double>>*,
                                                                     const Dual<Dual<double>>*, Dual<Dual<double>>*) const;

}  // namespace flatsos::plugin
