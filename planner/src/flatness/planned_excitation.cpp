#include "flatsos/planner/planned_excitation.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace flatsos::planner {

namespace {
class MuscleOfPlan final : public plugin::ExcitationSignal {
 public:
  MuscleOfPlan(std::shared_ptr<const PlannedExcitation> plan, int muscle) : plan_(std::move(plan)), muscle_(muscle) {}
  double value(double time_s) const override { return plan_->excitation(muscle_, time_s); }

 private:
  std::shared_ptr<const PlannedExcitation> plan_;  // keeps the plan, its map and its model alive
  int muscle_;
};
}  // namespace

std::shared_ptr<const PlannedExcitation> PlannedExcitation::create(FlatOutputMap flat, JointPath path,
                                                                   SplineTrajectory Y, double start_time_s) {
  if (Y.signals() != flat.numFlatOutputs())
    throw std::invalid_argument("planned excitation: " + std::to_string(Y.signals()) + " flat-output signals for " +
                                std::to_string(flat.numFlatOutputs()) + " flat outputs");
  if (std::abs(Y.duration() - path.duration_s) > 1e-12 * path.duration_s)
    throw std::invalid_argument("planned excitation: the flat outputs last " + std::to_string(Y.duration()) +
                                " s, the joint path " + std::to_string(path.duration_s) + " s");
  if (path.numJoints() != flat.numJoints())
    throw std::invalid_argument("planned excitation: the joint path has " + std::to_string(path.numJoints()) +
                                " joints, the model " + std::to_string(flat.numJoints()));
  return std::shared_ptr<const PlannedExcitation>(
      new PlannedExcitation(std::move(flat), std::move(path), std::move(Y), start_time_s));
}

PlannedExcitation::PlannedExcitation(FlatOutputMap flat, JointPath path, SplineTrajectory Y, double start_time_s)
    : flat_(std::move(flat)),
      path_(std::move(path)),
      Y_(std::move(Y)),
      start_time_s_(start_time_s),
      workspace_(flat_.makeWorkspace()) {}

const MusclePoint& PlannedExcitation::evaluateLocked(double time_s) const {
  if (time_s != cached_time_) {
    const double t = std::clamp(time_s - start_time_s_, 0.0, path_.duration_s);
    cached_ = flat_.inverse(workspace_, path_.jet(t, 5), Y_.jet(t, 3));
    cached_time_ = time_s;
    ++evaluations_;
  }
  return cached_;
}

MusclePoint PlannedExcitation::at(double time_s) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return evaluateLocked(time_s);
}

double PlannedExcitation::excitation(int muscle, double time_s) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return evaluateLocked(time_s).excitation[muscle];
}

std::shared_ptr<const plugin::ExcitationSignal> PlannedExcitation::signal(int muscle) const {
  if (muscle < 0 || muscle >= flat_.numMuscles())
    throw std::out_of_range("planned excitation: no muscle " + std::to_string(muscle));
  return std::make_shared<MuscleOfPlan>(shared_from_this(), muscle);
}

int PlannedExcitation::evaluations() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return evaluations_;
}

}  // namespace flatsos::planner
