#include "flatsos/plugin/force/excitation_signal.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace flatsos::plugin {

ExcitationPolynomial ExcitationPolynomial::constant(double excitation) {
  ExcitationPolynomial p;
  p.coefficients[0] = excitation;
  return p;
}

double ExcitationPolynomial::value(double time_s) const {
  if (count == 1) return coefficients[0];  // a held constant: read at every integrator stage
  const double s = std::clamp((time_s - start_time_s) / duration_s, 0.0, 1.0);
  double v = 0.0;
  for (int k = count - 1; k >= 0; --k) v = v * s + coefficients[static_cast<std::size_t>(k)];
  return v;
}

void ExcitationPolynomial::validate() const {
  if (count < 1 || count > kMaxCoefficients)
    throw std::invalid_argument("excitation polynomial: " + std::to_string(count) + " coefficients, need 1 to " +
                                std::to_string(kMaxCoefficients));
  for (int k = 0; k < count; ++k)
    if (!std::isfinite(coefficients[static_cast<std::size_t>(k)]))
      throw std::invalid_argument("excitation polynomial: coefficient " + std::to_string(k) + " is not finite");
  if (!std::isfinite(start_time_s)) throw std::invalid_argument("excitation polynomial: start time is not finite");
  if (!(duration_s > 0.0) || !std::isfinite(duration_s))
    throw std::invalid_argument("excitation polynomial: duration must be a finite time > 0 s");
}

namespace {
class DelayedSignal final : public ExcitationSignal {
 public:
  DelayedSignal(std::shared_ptr<const ExcitationSignal> signal, double delay_s)
      : signal_(std::move(signal)), delay_s_(delay_s) {}
  double value(double time_s) const override { return signal_->value(time_s - delay_s_); }

 private:
  std::shared_ptr<const ExcitationSignal> signal_;
  double delay_s_;
};
}  // namespace

ExcitationInput delayed(const ExcitationInput& input, double delay_s) {
  ExcitationInput out{input.piece, nullptr};
  out.piece.start_time_s += delay_s;
  if (input.signal) out.signal = std::make_shared<DelayedSignal>(input.signal, delay_s);
  return out;
}

namespace {
// Times finite and strictly increasing, values finite, as many of each, at least one.
void check_samples(const std::vector<double>& times_s, const std::vector<double>& values) {
  if (times_s.empty() || times_s.size() != values.size())
    throw std::invalid_argument("excitation signal: need as many values as times, at least one (got " +
                                std::to_string(times_s.size()) + " times, " + std::to_string(values.size()) + " values)");
  for (std::size_t i = 0; i < times_s.size(); ++i) {
    if (!std::isfinite(times_s[i]) || !std::isfinite(values[i]))
      throw std::invalid_argument("excitation signal: sample " + std::to_string(i) + " is not finite");
    if (i > 0 && !(times_s[i] > times_s[i - 1]))
      throw std::invalid_argument("excitation signal: times must increase strictly (sample " + std::to_string(i) + ")");
  }
}
}  // namespace

PiecewiseLinearSignal::PiecewiseLinearSignal(std::vector<double> times_s, std::vector<double> values)
    : times_s_(std::move(times_s)), values_(std::move(values)) {
  check_samples(times_s_, values_);
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

PiecewiseConstantSignal::PiecewiseConstantSignal(std::vector<double> times_s, std::vector<double> values)
    : times_s_(std::move(times_s)), values_(std::move(values)) {
  check_samples(times_s_, values_);
}

double PiecewiseConstantSignal::value(double time_s) const {
  const auto after = std::upper_bound(times_s_.begin(), times_s_.end(), time_s) - times_s_.begin();
  return after == 0 ? 0.0 : values_[static_cast<std::size_t>(after - 1)];
}

}  // namespace flatsos::plugin
