#include "settling_tracker.hpp"

#include <cmath>

namespace flatsos::planner::detail {

SettlingTracker::SettlingTracker(const plugin::MusculoskeletalModel& model,
                                 std::vector<double> starts, std::vector<Eigen::VectorXd> targets,
                                 double tolerance_rad, double slider_tolerance_m)
    : model_(model),
      starts_(std::move(starts)),
      targets_(std::move(targets)),
      tolerance_rad_(tolerance_rad),
      slider_tolerance_m_(slider_tolerance_m),
      q_rad_(model.numJoints()) {
  settled_.reserve(starts_.size());
}

void SettlingTracker::closeWindowsBefore(double t) {
  while (window_ + 1 < starts_.size() && t >= starts_[window_ + 1]) {
    settled_.push_back(inside_ ? inside_since_ : -1.0);  // -1 too for a window without rows
    inside_ = false;
    ++window_;
  }
}

void SettlingTracker::observe(const SimTK::State& state) {
  const double t = state.getTime();
  closeWindowsBefore(t);
  model_.jointAngles(state, q_rad_);
  bool inside = true;
  const auto& joints = model_.description().joints;
  for (int j = 0; j < q_rad_.size() && inside; ++j) {
    const double tolerance =
        joints[static_cast<std::size_t>(j)].isSlider() ? slider_tolerance_m_ : tolerance_rad_;
    inside = std::abs(q_rad_[j] - targets_[window_][j]) <= tolerance;
  }
  if (inside && !inside_) inside_since_ = t;
  inside_ = inside;
  any_row_ = true;
}

std::vector<double> SettlingTracker::settledTimes() const {
  std::vector<double> out = settled_;
  if (any_row_) out.push_back(inside_ ? inside_since_ : -1.0);
  return out;
}

}  // namespace flatsos::planner::detail
