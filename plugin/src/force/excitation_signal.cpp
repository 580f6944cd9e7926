#include "flatsos/plugin/force/excitation_signal.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace flatsos::plugin {

PiecewiseLinearSignal::PiecewiseLinearSignal(std::vector<double> times_s, std::vector<double> values)
    : times_s_(std::move(times_s)), values_(std::move(values)) {
  if (times_s_.empty() || times_s_.size() != values_.size())
    throw std::invalid_argument("excitation signal: need as many values as times, at least one (got " +
                                std::to_string(times_s_.size()) + " times, " +
                                std::to_string(values_.size()) + " values)");
  for (std::size_t i = 0; i < times_s_.size(); ++i) {
    if (!std::isfinite(times_s_[i]) || !std::isfinite(values_[i]))
      throw std::invalid_argument("excitation signal: sample " + std::to_string(i) +
                                  " is not finite");
    if (i > 0 && !(times_s_[i] > times_s_[i - 1]))
      throw std::invalid_argument("excitation signal: times must increase strictly (sample " +
                                  std::to_string(i) + ")");
  }
}

double PiecewiseLinearSignal::value(double time_s) const {
  if (time_s <= times_s_.front()) return values_.front();
  if (time_s >= times_s_.back()) return values_.back();
  const auto hi = static_cast<std::size_t>(
      std::upper_bound(times_s_.begin(), times_s_.end(), time_s) - times_s_.begin());
  const std::size_t lo = hi - 1;
  const double w = (time_s - times_s_[lo]) / (times_s_[hi] - times_s_[lo]);
  return (1.0 - w) * values_[lo] + w * values_[hi];
}

}  // namespace flatsos::plugin
