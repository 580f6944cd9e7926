#pragma once
// The receding-horizon controller's disturbance observer: a first-order filter of the joint
// torque the plant's muscles did not deliver,
//   w_k = ID(q, qd, qdd)_measured - R(q) F_estimated          (N m per joint, at t_k),
//   d(t_k) = d(t_{k-1}) + (1 - exp(-gain (t_k - t_{k-1}))) (w_k - d(t_{k-1})),
// where F_estimated are the tendon forces of the planner's model's muscles driven by the
// excitations the controller applied along the measured motion (muscle_state_estimator.hpp).
// So w is whatever the model misses (muscle strength, moment arms, masses, an external push),
// and not the difference between a plan's muscle states and the plant's at the plan's start.
// Plans then ask the muscles for ID(path) - d. With the plant equal to the model, d stays 0.
//
// The gain is in 1/s (the rate at which d follows a constant w), so it means the same at any
// control period; the exponential step keeps the filter stable at any gain and period. 0
// disables it.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <Eigen/Core>

namespace flatsos::planner {

class DisturbanceObserver {
 public:
  /// Throws std::invalid_argument for joints < 1 or a gain that is not a finite number >= 0.
  DisturbanceObserver(int joints, double gain_per_s);

  bool enabled() const { return gain_per_s_ > 0.0; }
  double gainPerSecond() const { return gain_per_s_; }
  /// The integral state d (N m per joint): the joint torque the muscles need not produce.
  const Eigen::VectorXd& torqueOffset_N_m() const { return offset_N_m_; }

  /// Moves d toward the measured disturbance w (N m per joint) over `elapsed_s` >= 0. A w that is
  /// not finite leaves d unchanged (the planner then reports the bad measurement). Throws
  /// std::invalid_argument for a wrong size or a negative time.
  void follow(const Eigen::VectorXd& measured_disturbance_N_m, double elapsed_s);
  void reset() { offset_N_m_.setZero(); }

 private:
  double gain_per_s_;
  Eigen::VectorXd offset_N_m_;
};

}  // namespace flatsos::planner
