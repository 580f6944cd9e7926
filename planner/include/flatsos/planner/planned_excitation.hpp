#pragma once
// Excitation signals that apply a plan to the Simbody muscles: n_j(t) from the exact inverse map
// of a flat trajectory, evaluated at the integrator's own times (no interpolation error).
// All muscles of one plan share one evaluation per time (a one-entry cache: an integrator asks
// every muscle at the same time). Not thread-safe: one simulation per plan object.

#include <memory>
#include <vector>

#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/joint_paths.hpp"
#include "flatsos/plugin/force/excitation_signal.hpp"

namespace flatsos::planner {

class PlannedExcitation : public std::enable_shared_from_this<PlannedExcitation> {
 public:
  /// The plan's time 0 is simulation time `start_time_s`; after the plan's end the excitation of
  /// its end is held.
  static std::shared_ptr<PlannedExcitation> create(const FlatOutputMap& flat, JointPath path,
                                                   std::vector<Polynomial> Y, double start_time_s = 0.0);
  /// Muscle quantities of the plan at simulation time t (cached for the last t).
  const MusclePoint& at(double time_s) const;
  /// The signal to give muscle j (HillMuscle::setExcitationSignal).
  std::shared_ptr<const plugin::ExcitationSignal> signal(int muscle) const;
  int evaluations() const { return evaluations_; }

 private:
  PlannedExcitation(const FlatOutputMap& flat, JointPath path, std::vector<Polynomial> Y, double start_time_s);
  const FlatOutputMap& flat_;
  JointPath path_;
  std::vector<Polynomial> Y_;
  double start_time_s_;
  mutable double cached_time_ = -1e300;
  mutable MusclePoint cached_;
  mutable int evaluations_ = 0;
};

}  // namespace flatsos::planner
