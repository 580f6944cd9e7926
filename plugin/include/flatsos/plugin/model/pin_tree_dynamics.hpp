#pragma once
// Inverse dynamics of a model's tree of pin and slider joints by the recursive Newton-Euler
// algorithm (Featherstone, Rigid Body Dynamics Algorithms, 2008, ch. 5): an outward pass for each
// body's angular velocity, angular acceleration and origin acceleration, an inward pass summing
// the forces and moments each joint transmits, and each joint's generalized force: a pin's torque
// is the moment's component along its axis, a slider's force (N) the force's component along
// its axis. The same tree, masses and frames that
// MusculoskeletalModel builds in Simbody (tested against Simbody's inverse dynamics), but
// evaluated in caller-owned scratch: no heap allocation per call, which the receding-horizon
// controller needs (Simbody's calcResidualForceIgnoringConstraints allocates ~11 temporaries per
// call internally, and the controller calls it ~20 times per control period). Written once for
// any scalar type: with dual numbers the same recursion gives the torques' time derivatives along
// a motion and their derivatives with respect to it, exactly (what a planner that moves the
// joint path needs).

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <array>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "flatsos/plugin/model/joint_limit.hpp"
#include "flatsos/plugin/model/model_description.hpp"

namespace flatsos::plugin {

class PinTreeDynamics {
 public:
  /// Per-body kinematics and transmitted loads of one evaluation (ground frame), in the scalar
  /// type of the evaluation (double, or dual numbers for exact derivatives).
  template <class S>
  struct ScratchOf {
    struct Body {
      Eigen::Matrix<S, 3, 3> rotation;             ///< body frame -> ground
      Eigen::Matrix<S, 3, 1> origin_m, axis;       ///< body origin (a pin's joint position) and joint axis in ground
      Eigen::Matrix<S, 3, 1> angular_velocity, angular_acceleration, origin_acceleration;
      Eigen::Matrix<S, 3, 1> force_N, moment_N_m;  ///< transmitted through the joint (moment about the origin)
    };
    std::vector<Body> bodies;
  };
  using Scratch = ScratchOf<double>;

  /// From a validated description (joints listed parents first).
  explicit PinTreeDynamics(const ModelDescription& description);

  int numJoints() const { return static_cast<int>(joints_.size()); }
  Scratch makeScratch() const;

  /// tau = M(q) qdd + C(q, qd) qd + g(q) - tau_limit(q, qd): the joint torques the muscles must
  /// supply for qdd at (q, qd), under gravity and the joints' limit torques (joint_limit.hpp; zero
  /// inside every range). Sizes must equal numJoints() and scratch come from makeScratch()
  /// (checked by the caller, MusculoskeletalModel).
  void inverseDynamics(Scratch& scratch, const Eigen::Ref<const Eigen::VectorXd>& q_rad,
                       const Eigen::Ref<const Eigen::VectorXd>& qd_rad_per_s,
                       const Eigen::Ref<const Eigen::VectorXd>& qdd_rad_per_s2,
                       Eigen::Ref<Eigen::VectorXd> tau_N_m) const;
  /// The rigid bodies' share alone, M(q) qdd + C(q, qd) qd + g(q): smooth (analytic) in its
  /// arguments, unlike the limit torques, so differences in time may be taken of it.
  void rigidBodyInverseDynamics(Scratch& scratch, const Eigen::Ref<const Eigen::VectorXd>& q_rad,
                                const Eigen::Ref<const Eigen::VectorXd>& qd_rad_per_s,
                                const Eigen::Ref<const Eigen::VectorXd>& qdd_rad_per_s2,
                                Eigen::Ref<Eigen::VectorXd> tau_N_m) const;
  /// True when some joint has a limit torque.
  bool hasJointLimits() const { return has_limits_; }
  /// The limit torques tau_limit(q, qd) (N entries; 0 for joints without a limit).
  void jointLimitTorques(const Eigen::Ref<const Eigen::VectorXd>& q_rad,
                         const Eigen::Ref<const Eigen::VectorXd>& qd_rad_per_s, Eigen::Ref<Eigen::VectorXd> tau_N_m) const;
  /// The limit torques and their first two time derivatives along a motion with joint jet q_jet
  /// (N x k, q and its derivatives; columns beyond k are 0, and k >= 4 makes it exact: the
  /// damper's second derivative needs q'''), exactly (dual numbers): into out (N x 3). Allocates
  /// nothing.
  void jointLimitTorqueJet(const Eigen::Ref<const Eigen::MatrixXd>& q_jet, Eigen::Ref<Eigen::MatrixXd> out) const;
  /// The same in another scalar type (instantiated for double and nested dual numbers,
  /// dual_number.hpp); q, qd, qdd and tau have numJoints() entries, scratch is resized.
  template <class S>
  void inverseDynamicsOf(ScratchOf<S>& scratch, const S* q_rad, const S* qd_rad_per_s, const S* qdd_rad_per_s2,
                         S* tau_N_m) const;

  /// tau at (q, qd, qdd) and its Jacobian with respect to x = (q, qd, qdd), exactly (dual
  /// numbers): N x 3N, columns ordered by kind [q_1..q_N | qd_1..qd_N | qdd_1..qdd_N]. What an
  /// optimizer over joint trajectories (direct collocation with a free joint path) needs.
  Eigen::VectorXd inverseDynamicsJacobian(const Eigen::Ref<const Eigen::VectorXd>& q_rad,
                                          const Eigen::Ref<const Eigen::VectorXd>& qd_rad_per_s,
                                          const Eigen::Ref<const Eigen::VectorXd>& qdd_rad_per_s2,
                                          Eigen::MatrixXd& jacobian) const;
  /// sum_i w_i d2 tau_i / dx2 for the same x (3N x 3N, symmetric), exactly (second-order dual
  /// numbers, one pass per pair of entries). tau = M(q) qdd + C(q, qd) qd + g(q) is linear in
  /// qdd, so the qd-qdd and qdd-qdd blocks are zero and not evaluated.
  Eigen::MatrixXd inverseDynamicsHessian(const Eigen::Ref<const Eigen::VectorXd>& q_rad,
                                         const Eigen::Ref<const Eigen::VectorXd>& qd_rad_per_s,
                                         const Eigen::Ref<const Eigen::VectorXd>& qdd_rad_per_s2,
                                         const Eigen::Ref<const Eigen::VectorXd>& weights) const;

  /// tau and its first two time derivatives along a motion with joint jet `q_jet` (N x 5: q and
  /// its first four time derivatives), exactly (second-order dual numbers along the motion, no
  /// differences in time): N x 3.
  Eigen::MatrixXd torqueJet(const Eigen::Ref<const Eigen::MatrixXd>& q_jet) const;
  /// The same and its derivatives with respect to the jet's entries: gradient(3 * i + k,
  /// 5 * r + l) = d (d^k tau_i / dt^k) / d (d^l q_r / dt^l), a 3N x 5N matrix.
  Eigen::MatrixXd torqueJet(const Eigen::Ref<const Eigen::MatrixXd>& q_jet, Eigen::MatrixXd& gradient) const;
  /// The Hessian of sum_ik weights(i, k) d^k tau_i / dt^k in the jet's entries (5N x 5N,
  /// symmetric, index 5 r + l as the gradient's columns), exactly: one pass of fourth-order dual
  /// numbers per pair of entries. tau is linear in qdd, so d2 tau''/dt2 is linear in q''' and
  /// q'''' with coefficients of q and qd alone: the pairs of orders (1..4, 4), (2..3, 3) are zero
  /// and not evaluated (33 passes of 55 for two joints).
  Eigen::MatrixXd torqueJetHessian(const Eigen::Ref<const Eigen::MatrixXd>& q_jet,
                                   const Eigen::Ref<const Eigen::MatrixXd>& weights) const;

 private:
  struct Joint {
    int parent = -1;                       ///< joint index of the parent body; -1: ground
    bool slider = false;                   ///< translates along the axis instead of turning about it
    Eigen::Vector3d location_in_parent_m;  ///< joint origin in the parent's frame
    Eigen::Vector3d axis;                  ///< unit axis, parent frame (fixed in the child too)
    Eigen::Matrix3d axis_cross, axis_cross_squared;  ///< K (K v = axis x v) and K^2, for Rodrigues
    double mass_kg = 0.0;
    Eigen::Vector3d mass_center_m;         ///< child body frame
    Eigen::Matrix3d inertia_about_com_kg_m2;  ///< child body frame
    JointLimitTorque limit;
    std::array<double, 2> range_rad{};
  };
  template <class S>
  using BodyOf = typename ScratchOf<S>::Body;
  /// A body's rotation, origin, axis, velocities and accelerations from its parent's (nullptr:
  /// ground) and its joint's q, qd, qdd.
  template <class S>
  static void pinKinematicsOf(const Joint& j, const BodyOf<S>* parent, const S& q, const S& qd, const S& qdd, BodyOf<S>& b);
  template <class S>
  static void sliderKinematicsOf(const Joint& j, const BodyOf<S>* parent, const S& q, const S& qd, const S& qdd,
                                 BodyOf<S>& b);
  template <class S>
  void rigidBodyTorquesOf(ScratchOf<S>& scratch, const S* q, const S* qd, const S* qdd, S* tau) const;
  bool has_limits_ = false;
  std::vector<Joint> joints_;
  Eigen::Vector3d gravity_m_per_s2_;
};

}  // namespace flatsos::plugin
