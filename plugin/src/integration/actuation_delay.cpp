#include "flatsos/plugin/integration/actuation_delay.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace flatsos::plugin {

namespace {
constexpr double kDueTolerance_s = 1e-9;  // a command due within this of a time is due there
}

ActuationDelay::ActuationDelay(const MusculoskeletalModel& plant, double delay_s,
                               double control_period_s)
    : plant_(plant), delay_s_(delay_s) {
  if (!(delay_s >= 0.0) || !std::isfinite(delay_s))
    throw std::invalid_argument("actuation delay: must be a finite time >= 0 s (got " +
                                std::to_string(delay_s) + ")");
  if (!(control_period_s > 0.0) || !std::isfinite(control_period_s))
    throw std::invalid_argument("actuation delay: the control period must be > 0 s");
  if (!active()) return;
  // At most one command per period is sent, and each stays on its way for delay_s.
  const auto capacity = static_cast<std::size_t>(std::ceil(delay_s / control_period_s)) + 2;
  const auto muscles = static_cast<std::size_t>(plant.numMuscles());
  ring_.assign(capacity, Command{0.0, std::vector<ExcitationInput>(muscles)});
  in_effect_.resize(muscles);
}

void ActuationDelay::keepInputsInEffect(const SimTK::State& state) {
  for (int j = 0; j < plant_.numMuscles(); ++j)
    in_effect_[static_cast<std::size_t>(j)] = plant_.muscle(j).getExcitationInput(state);
}

void ActuationDelay::holdBack(SimTK::State& state) {
  if (count_ == ring_.size())  // more commands than periods in a delay: the closed loop's bug
    throw std::logic_error("actuation delay: more commands on their way than periods in the delay");
  Command& c = ring_[(head_ + count_) % ring_.size()];
  ++count_;
  c.due_s = state.getTime() + delay_s_;
  for (int j = 0; j < plant_.numMuscles(); ++j) {
    const auto k = static_cast<std::size_t>(j);
    c.inputs[k] = delayed(plant_.muscle(j).getExcitationInput(state), delay_s_);
    plant_.muscle(j).setExcitationInput(state, in_effect_[k]);
  }
}

double ActuationDelay::nextDue() const {
  return count_ == 0 ? std::numeric_limits<double>::infinity() : ring_[head_].due_s;
}

void ActuationDelay::applyDue(SimTK::State& state) {
  while (count_ > 0 && ring_[head_].due_s <= state.getTime() + kDueTolerance_s) {
    const Command& c = ring_[head_];
    for (int j = 0; j < plant_.numMuscles(); ++j)
      plant_.muscle(j).setExcitationInput(state, c.inputs[static_cast<std::size_t>(j)]);
    head_ = (head_ + 1) % ring_.size();
    --count_;
  }
}

}  // namespace flatsos::plugin
