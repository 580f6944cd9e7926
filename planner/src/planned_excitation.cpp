#include "flatsos/planner/planned_excitation.hpp"

#include <algorithm>

namespace flatsos::planner {

namespace {
class MuscleOfPlan final : public plugin::ExcitationSignal {
 public:
  MuscleOfPlan(std::shared_ptr<const PlannedExcitation> plan, int muscle) : plan_(std::move(plan)), muscle_(muscle) {}
  double value(double time_s) const override { return plan_->at(time_s).excitation[muscle_]; }

 private:
  std::shared_ptr<const PlannedExcitation> plan_;
  int muscle_;
};
}  // namespace

std::shared_ptr<PlannedExcitation> PlannedExcitation::create(const FlatOutputMap& flat, JointPath path,
                                                             std::vector<Polynomial> Y, double start_time_s) {
  return std::shared_ptr<PlannedExcitation>(new PlannedExcitation(flat, std::move(path), std::move(Y), start_time_s));
}

PlannedExcitation::PlannedExcitation(const FlatOutputMap& flat, JointPath path, std::vector<Polynomial> Y,
                                     double start_time_s)
    : flat_(flat), path_(std::move(path)), Y_(std::move(Y)), start_time_s_(start_time_s) {}

const MusclePoint& PlannedExcitation::at(double time_s) const {
  if (time_s != cached_time_) {
    const double t = std::clamp(time_s - start_time_s_, 0.0, path_.duration_s);
    Jet yj(static_cast<Eigen::Index>(Y_.size()), 3);
    for (std::size_t l = 0; l < Y_.size(); ++l)
      for (int k = 0; k < 3; ++k) yj(static_cast<Eigen::Index>(l), k) = Y_[l].derivativeAt(t, k);
    cached_ = flat_.inverse(path_.jet(t, 5), yj);
    cached_time_ = time_s;
    ++evaluations_;
  }
  return cached_;
}

std::shared_ptr<const plugin::ExcitationSignal> PlannedExcitation::signal(int muscle) const {
  return std::make_shared<MuscleOfPlan>(shared_from_this(), muscle);
}

}  // namespace flatsos::planner
