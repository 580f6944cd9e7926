#pragma once
// A joint motion for the receding-horizon controller to follow (tracking): a measured motion
// made smooth as OpenSim's tools do (one natural quintic spline per coordinate), or a plan's
// joint path. Evaluated with derivatives up to the fourth, which the inverse map needs.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "flatsos/planner/joint_paths.hpp"
#include "flatsos/plugin/io/motion_processing.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace flatsos::planner {

class JointReference {
 public:
  /// The model's coordinates (by OpenSim name) of a processed motion, from its first to its last
  /// report time (rad, a slider's m). Beyond them the splines go on: through the padding of a
  /// filtered motion, else their end intervals continued. Throws std::invalid_argument naming a
  /// coordinate the motion lacks.
  static JointReference fromMotion(const plugin::MusculoskeletalModel& model, const plugin::ProcessedCoordinates& motion);
  /// A plan's joint path whose t = 0 is at start_time_s; before it, its start posture at rest;
  /// after its end, its end posture at rest.
  /// Throws std::invalid_argument for a path without joints or duration, or one that is itself
  /// a tracking path.
  static JointReference fromPath(JointPath path, double start_time_s);

  int numJoints() const { return joints_; }
  double startTime_s() const { return start_s_; }
  double endTime_s() const { return end_s_; }
  /// Derivatives 0 .. out.cols() - 1 (at most 6) of every joint at time t into `out` (joints
  /// rows); allocates nothing. Throws std::invalid_argument for a wrong shape or a t not finite.
  void jetInto(double t, Eigen::Ref<Jet> out) const;
  Jet jet(double t, int orders) const;
  /// Derivative `order` (0..5) of one joint at t.
  double derivative(int joint, double t, int order) const;

 private:
  JointReference() = default;
  int joints_ = 0;
  double start_s_ = 0.0, end_s_ = 0.0;
  std::vector<plugin::NaturalQuinticSpline> splines_;  ///< a motion: per joint
  std::optional<JointPath> path_;                      ///< a plan
};

}  // namespace flatsos::planner
