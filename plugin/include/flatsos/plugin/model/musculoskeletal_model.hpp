#pragma once
// A Simbody system built from a ModelDescription: a tree of Pin and Slider mobilizers with
// gravity, the joints' limit torques (where the description gives them) and one
// HillMuscle per muscle. Vectors are in the description's order (joints = generalized
// coordinates, muscles). Not copyable: Simbody subsystems refer to each other. "Angles" and
// "torques" below are generalized: a slider's coordinate is in m (speed m/s) and its torque is a
// force in N.
//
// Immutable once built and meant to be shared (std::shared_ptr<const MusculoskeletalModel>):
// every const member is safe to call from several threads at once. Calculations that need
// scratch (the mass matrix through a Simbody State, inverse dynamics) take a ModelWorkspace that
// the caller owns (one per thread); the overloads without one make a temporary workspace per call.
// Simulations of one model (the project's steppers, mechanicalEnergy, the joint sensors) take
// turns across threads: Simbody realizes a System's forces through one shared task object. Code
// that realizes this model's States to Stage::Dynamics itself, from several threads, must
// serialize that too (or use one model per thread).

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Simbody.h>

#include "flatsos/plugin/force/hill_muscle.hpp"
#include "flatsos/plugin/model/model_description.hpp"
#include "flatsos/plugin/model/model_workspace.hpp"
#include "flatsos/plugin/model/pin_tree_dynamics.hpp"

namespace flatsos::plugin {

/// A torque tau(t) (N m, a function of time; N along a slider) applied on one joint, e.g. a
/// disturbance pulse.
struct ExternalJointTorque {
  int joint = -1;  ///< joint index (description order)
  std::shared_ptr<const ExcitationSignal> torque_N_m;
};

class MusculoskeletalModel {
 public:
  /// Builds and realizes the topology. Throws ModelFileError if the description is invalid,
  /// std::invalid_argument for an external torque on a joint that does not exist or without a
  /// signal.
  explicit MusculoskeletalModel(ModelDescription description, std::vector<ExternalJointTorque> external_torques = {});
  static std::shared_ptr<const MusculoskeletalModel> fromFile(const std::string& path);
  MusculoskeletalModel(const MusculoskeletalModel&) = delete;
  MusculoskeletalModel& operator=(const MusculoskeletalModel&) = delete;

  const ModelDescription& description() const { return description_; }
  /// Implausible values of the description (plausibility_warnings: unit mix-ups); empty for a
  /// model in SI units. Programs print them and store them in their summaries.
  const std::vector<std::string>& warnings() const { return warnings_; }
  int numJoints() const { return description_.numJoints(); }
  int numMuscles() const { return description_.numMuscles(); }

  const SimTK::MultibodySystem& system() const { return system_; }
  SimTK::MultibodySystem& updSystem() { return system_; }
  const SimTK::SimbodyMatterSubsystem& matter() const { return matter_; }
  const SimTK::MobilizedBody& joint(int i) const { return joints_.at(i); }
  const HillMuscle& muscle(int j) const { return muscles_.at(j); }
  const PinTreeDynamics& pinTree() const { return tree_; }

  /// A fresh default state (topology realized; q = qd = 0, muscle defaults).
  SimTK::State defaultState() const { return system_.getDefaultState(); }
  /// Scratch for massMatrix and inverseDynamics (one per thread).
  ModelWorkspace makeWorkspace() const { return ModelWorkspace(*this); }

  // --- state access in description order ---
  Eigen::VectorXd jointAngles(const SimTK::State& s) const;  ///< q, rad
  Eigen::VectorXd jointSpeeds(const SimTK::State& s) const;  ///< qd, rad/s
  /// The same into `out` (N entries; allocates nothing). Throws std::invalid_argument for a wrong size.
  void jointAngles(const SimTK::State& s, Eigen::Ref<Eigen::VectorXd> q_rad) const;
  void jointSpeeds(const SimTK::State& s, Eigen::Ref<Eigen::VectorXd> qd_rad_per_s) const;
  void setJointAngles(SimTK::State& s, const Eigen::VectorXd& q_rad) const;
  void setJointSpeeds(SimTK::State& s, const Eigen::VectorXd& qd_rad_per_s) const;
  Eigen::VectorXd activations(const SimTK::State& s) const;
  Eigen::VectorXd tendonLengths(const SimTK::State& s) const;
  Eigen::VectorXd tendonForces(const SimTK::State& s) const;
  Eigen::VectorXd excitations(const SimTK::State& s) const;  ///< clamped, at the state's time
  void setActivations(SimTK::State& s, const Eigen::VectorXd& a) const;
  void setTendonLengths(SimTK::State& s, const Eigen::VectorXd& ls_m) const;
  void setExcitations(SimTK::State& s, const Eigen::VectorXd& n) const;  ///< held values

  // --- model quantities ---
  /// True when every muscle's moment arms are the same in every posture.
  bool hasConstantMomentArms() const { return description_.hasConstantMomentArms(); }
  /// A (N x m) of a model with constant moment arms; throws std::logic_error otherwise.
  const Eigen::MatrixXd& momentArmMatrix() const;
  /// R(q) (N x m): R(i, j) = r_ij(q) = -dL_j/dq_i, moment arm of muscle j about joint i.
  Eigen::MatrixXd momentArmMatrix(const Eigen::VectorXd& q_rad) const;
  /// Muscle j's path: L(q), moment arms, their Jacobians and time jets.
  const muscles::MusculotendonPath& musclePath(int muscle) const;
  /// Musculotendon lengths L(q).
  Eigen::VectorXd musculotendonLengths(const Eigen::VectorXd& q_rad) const;
  /// One muscle's L(q) (allocates nothing). Throws std::out_of_range for a muscle that does not
  /// exist, std::invalid_argument for a q of the wrong size.
  double musculotendonLength(int muscle, const Eigen::Ref<const Eigen::VectorXd>& q_rad) const;
  /// Joint torques tau = A F of the given tendon forces (constant moment arms only).
  Eigen::VectorXd muscleTorques(const Eigen::VectorXd& tendon_forces_N) const;
  /// Joint torques tau = R(q) F.
  Eigen::VectorXd muscleTorques(const Eigen::VectorXd& q_rad, const Eigen::VectorXd& tendon_forces_N) const;
  /// Mass matrix M(q) from Simbody.
  Eigen::MatrixXd massMatrix(ModelWorkspace& workspace, const Eigen::VectorXd& q_rad) const;
  Eigen::MatrixXd massMatrix(const Eigen::VectorXd& q_rad) const;
  /// Inverse dynamics: the joint torques the muscles must supply (external torques excluded),
  /// tau = M(q) qdd + C(q, qd) qd + g(q) - tau_limit(q, qd), by recursive Newton-Euler on the pin
  /// tree (pin_tree_dynamics.hpp; agrees with Simbody's to round-off); tau_limit are the joints'
  /// limit torques (joint_limit.hpp), zero inside every range. Allocates nothing.
  void inverseDynamics(ModelWorkspace& workspace, const Eigen::Ref<const Eigen::VectorXd>& q_rad,
                       const Eigen::Ref<const Eigen::VectorXd>& qd_rad_per_s,
                       const Eigen::Ref<const Eigen::VectorXd>& qdd_rad_per_s2, Eigen::Ref<Eigen::VectorXd> tau_N_m) const;
  Eigen::VectorXd inverseDynamics(ModelWorkspace& workspace, const Eigen::VectorXd& q_rad,
                                  const Eigen::VectorXd& qd_rad_per_s, const Eigen::VectorXd& qdd_rad_per_s2) const;
  Eigen::VectorXd inverseDynamics(const Eigen::VectorXd& q_rad, const Eigen::VectorXd& qd_rad_per_s,
                                  const Eigen::VectorXd& qdd_rad_per_s2) const;

  /// The rigid bodies' share alone, M(q) qdd + C(q, qd) qd + g(q) (no limit torques): analytic
  /// in (q, qd, qdd), so differences in time may be taken of it. Allocates nothing.
  void rigidBodyInverseDynamics(ModelWorkspace& workspace, const Eigen::Ref<const Eigen::VectorXd>& q_rad,
                                const Eigen::Ref<const Eigen::VectorXd>& qd_rad_per_s,
                                const Eigen::Ref<const Eigen::VectorXd>& qdd_rad_per_s2,
                                Eigen::Ref<Eigen::VectorXd> tau_N_m) const;
  /// True when some joint has a limit torque.
  bool hasJointLimits() const { return tree_.hasJointLimits(); }

  /// Total mechanical energy of the multibody system (kinetic + gravitational + the joint limits'
  /// springs), J.
  double mechanicalEnergy(const SimTK::State& s) const;

 private:
  void checkSize(const Eigen::Ref<const Eigen::VectorXd>& v, int n, const char* what) const;
  void checkWorkspace(const ModelWorkspace& workspace) const;
  void checkInverseDynamics(const ModelWorkspace& workspace, const Eigen::Ref<const Eigen::VectorXd>& q,
                            const Eigen::Ref<const Eigen::VectorXd>& qd, const Eigen::Ref<const Eigen::VectorXd>& qdd,
                            const Eigen::Ref<Eigen::VectorXd>& tau) const;
  const SimTK::State& realizeVelocity(ModelWorkspace& workspace, const Eigen::VectorXd& q,
                                      const Eigen::VectorXd& qd) const;

  ModelDescription description_;
  std::vector<std::string> warnings_;
  SimTK::MultibodySystem system_;
  SimTK::SimbodyMatterSubsystem matter_;
  SimTK::GeneralForceSubsystem forces_;
  SimTK::Force::Gravity gravity_;
  std::vector<SimTK::MobilizedBody> joints_;
  std::vector<HillMuscle> muscles_;
  Eigen::MatrixXd moment_arms_;  ///< empty when a muscle's moment arms depend on posture
  std::vector<muscles::MusculotendonPath> paths_;
  PinTreeDynamics tree_;
};

}  // namespace flatsos::plugin
