#pragma once
// Inverse dynamics of a model's tree of pin joints by the recursive Newton-Euler algorithm:
// an outward pass for each body's angular velocity, angular acceleration and origin
// acceleration, an inward pass summing the forces and moments each joint transmits, and each
// joint's torque as the moment's component along its axis. The same tree, masses and frames that
// MusculoskeletalModel builds in Simbody (tested against Simbody's inverse dynamics), but
// evaluated in caller-owned scratch: no heap allocation per call, which the receding-horizon
// controller needs (Simbody's calcResidualForceIgnoringConstraints allocates ~11 temporaries per
// call internally, and the controller calls it ~20 times per control period).

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "flatsos/plugin/model/model_description.hpp"

namespace flatsos::plugin {

class PinTreeDynamics {
 public:
  /// Per-body kinematics and transmitted loads of one evaluation (ground frame).
  struct Scratch {
    struct Body {
      Eigen::Matrix3d rotation;             ///< body frame -> ground
      Eigen::Vector3d origin_m, axis;       ///< joint position and axis in ground
      Eigen::Vector3d angular_velocity, angular_acceleration, origin_acceleration;
      Eigen::Vector3d force_N, moment_N_m;  ///< transmitted through the joint (moment about the origin)
    };
    std::vector<Body> bodies;
  };

  /// From a validated description (joints listed parents first).
  explicit PinTreeDynamics(const ModelDescription& description);

  int numJoints() const { return static_cast<int>(joints_.size()); }
  Scratch makeScratch() const;

  /// tau = M(q) qdd + C(q, qd) qd + g(q): the joint torques that produce qdd at (q, qd) under
  /// gravity alone. Sizes must equal numJoints() and scratch come from makeScratch() (checked
  /// by the caller, MusculoskeletalModel).
  void inverseDynamics(Scratch& scratch, const Eigen::Ref<const Eigen::VectorXd>& q_rad,
                       const Eigen::Ref<const Eigen::VectorXd>& qd_rad_per_s,
                       const Eigen::Ref<const Eigen::VectorXd>& qdd_rad_per_s2,
                       Eigen::Ref<Eigen::VectorXd> tau_N_m) const;

 private:
  struct Joint {
    int parent = -1;                       ///< joint index of the parent body; -1: ground
    Eigen::Vector3d location_in_parent_m;  ///< joint origin in the parent's frame
    Eigen::Vector3d axis;                  ///< unit axis, parent frame (fixed in the child too)
    double mass_kg = 0.0;
    Eigen::Vector3d mass_center_m;         ///< child body frame
    Eigen::Matrix3d inertia_about_com_kg_m2;  ///< child body frame
  };
  std::vector<Joint> joints_;
  Eigen::Vector3d gravity_m_per_s2_;
};

}  // namespace flatsos::plugin
