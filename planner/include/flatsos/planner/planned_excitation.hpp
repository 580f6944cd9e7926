#pragma once
// Excitation signals that apply a plan to the Simbody muscles: n_j(t) from the exact inverse map
// of a flat trajectory, evaluated at the integrator's own times (no interpolation error).
//
// The object owns everything it needs (a copy of the flat-output map, which shares the model;
// the joint path and flat outputs by value; its own inverse-dynamics workspace), so the signals
// stay valid in a SimTK::State for as long as the State holds them, whatever happened to the
// objects the plan was made from. All muscles of one plan share one evaluation per time (an
// integrator asks every muscle at the same time): a one-entry cache behind a mutex, so one plan
// may drive simulations in several threads (they then take turns).

#include <memory>
#include <mutex>
#include <vector>

#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/joint_paths.hpp"
#include "flatsos/planner/numerics/spline_trajectory.hpp"
#include "flatsos/plugin/force/excitation_signal.hpp"

namespace flatsos::planner {

class PlannedExcitation : public std::enable_shared_from_this<PlannedExcitation> {
 public:
  /// The plan's time 0 is simulation time `start_time_s`; after the plan's end the excitation of
  /// its end is held. Throws std::invalid_argument when the sizes or durations of the map, the
  /// joint path and the flat outputs disagree.
  static std::shared_ptr<const PlannedExcitation> create(FlatOutputMap flat, JointPath path, SplineTrajectory Y,
                                                         double start_time_s = 0.0);
  /// Muscle quantities of the plan at simulation time t.
  MusclePoint at(double time_s) const;
  /// Excitation of muscle j at simulation time t (what the signals return).
  double excitation(int muscle, double time_s) const;
  /// The signal to give muscle j (HillMuscle::setExcitationSignal). Throws std::out_of_range for
  /// a muscle the model does not have.
  std::shared_ptr<const plugin::ExcitationSignal> signal(int muscle) const;
  /// Inverse-map evaluations so far (cache misses).
  int evaluations() const;

 private:
  PlannedExcitation(FlatOutputMap flat, JointPath path, SplineTrajectory Y, double start_time_s);
  // Evaluates (or reuses) the point at time_s; the caller holds mutex_.
  const MusclePoint& evaluateLocked(double time_s) const;

  const FlatOutputMap flat_;
  const JointPath path_;
  const SplineTrajectory Y_;
  const double start_time_s_;
  // Scratch and cache: not part of the plan's value, hence mutable, guarded by mutex_.
  mutable std::mutex mutex_;
  mutable plugin::ModelWorkspace workspace_;
  mutable double cached_time_ = -1e300;
  mutable MusclePoint cached_;
  mutable int evaluations_ = 0;
};

}  // namespace flatsos::planner
