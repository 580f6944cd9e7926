#pragma once
// The receding-horizon controller's disturbance observer, with integral action:
//   d(t_k) = d(t_{k-1}) + gain (t_k - t_{k-1}) e_k,
// e_k = the joint torque the measured motion needs minus the one the plan in use predicted for
// t_k (its muscles were asked for exactly the latter), so e is what the plant did not deliver,
// whatever the cause (tendon, muscle strength, moment arms, masses, external torque). Plans then
// ask the muscles for ID(path) - d. A rest away from the target leaves the plan asking for
// acceleration the arm does not show, so d keeps moving: no steady offset.
//
// The gain is in 1/s (the rate at which d follows a constant error), so it means the same at
// any control period: the former per-step gain g at period delta is g / delta (the paper's arm
// at 0.05 s: gain 20 1/s = 1 per step). Measured stable on the arm for 10-40 1/s; 0 disables it.

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

  /// Integrates the prediction error `torque_error_N_m` (measured minus predicted, N m per joint)
  /// over `elapsed_s` >= 0. A non-finite error leaves d unchanged (the planner then reports the
  /// bad measurement). Throws std::invalid_argument for a wrong size or a negative time.
  void update(const Eigen::VectorXd& torque_error_N_m, double elapsed_s);
  void reset() { offset_N_m_.setZero(); }

 private:
  double gain_per_s_;
  Eigen::VectorXd offset_N_m_;
};

}  // namespace flatsos::planner
