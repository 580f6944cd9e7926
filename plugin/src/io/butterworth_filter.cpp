#include "flatsos/plugin/io/butterworth_filter.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace flatsos::plugin {

ThirdOrderFilterCoefficients third_order_butterworth_lowpass(double cutoff_hz, double sample_interval_s) {
  if (!(sample_interval_s > 0.0) || !std::isfinite(sample_interval_s))
    throw std::invalid_argument("Butterworth filter: sample_interval_s must be positive and finite, got " +
                                std::to_string(sample_interval_s));
  const double nyquist_hz = 0.5 / sample_interval_s;
  if (!(cutoff_hz > 0.0) || !(cutoff_hz < nyquist_hz))
    throw std::invalid_argument("Butterworth filter: cutoff_hz must lie in (0, " + std::to_string(nyquist_hz) +
                                ") Hz for this sample interval, got " + std::to_string(cutoff_hz));
  // Analog prototype 1 / (p^3 + 2 p^2 + 2 p + 1) with p = (1 - z^-1) / (W (1 + z^-1)) and the
  // pre-warped W = tan(pi fc T); multiplying through by W^3 (1 + z^-1)^3 gives these polynomials
  // in z^-1, normalised by the leading denominator coefficient (1 + W)(1 + W + W^2).
  const double w = std::tan(M_PI * cutoff_hz * sample_interval_s);
  const double w2 = w * w;
  const double w3 = w2 * w;
  const double lead = (w + 1.0) * (w2 + w + 1.0);
  ThirdOrderFilterCoefficients c;
  c.numerator = {w3 / lead, 3.0 * w3 / lead, 3.0 * w3 / lead, w3 / lead};
  c.denominator = {1.0, (3.0 * w3 + 2.0 * w2 - 2.0 * w - 3.0) / lead, (3.0 * w3 - 2.0 * w2 - 2.0 * w + 3.0) / lead,
                   (w - 1.0) * (w2 - w + 1.0) / lead};
  return c;
}

std::vector<double> filter_one_pass(const ThirdOrderFilterCoefficients& f, const std::vector<double>& x) {
  if (x.size() < 4)
    throw std::invalid_argument("Butterworth filter: needs at least 4 samples, got " + std::to_string(x.size()));
  std::vector<double> y(x.size());
  for (std::size_t i = 0; i < 3; ++i) y[i] = x[i];
  for (std::size_t i = 3; i < x.size(); ++i) {
    const double feed_forward =
        f.numerator[0] * x[i] + f.numerator[1] * x[i - 1] + f.numerator[2] * x[i - 2] + f.numerator[3] * x[i - 3];
    const double feedback = f.denominator[1] * y[i - 1] + f.denominator[2] * y[i - 2] + f.denominator[3] * y[i - 3];
    y[i] = feed_forward - feedback;
  }
  return y;
}

std::vector<double> lowpass_forward_backward(const std::vector<double>& signal, double cutoff_hz,
                                             double sample_interval_s) {
  for (std::size_t i = 0; i < signal.size(); ++i)
    if (!std::isfinite(signal[i]))
      throw std::invalid_argument("Butterworth filter: sample " + std::to_string(i) + " is not finite");
  const ThirdOrderFilterCoefficients f = third_order_butterworth_lowpass(cutoff_hz, sample_interval_s);
  std::vector<double> forward = filter_one_pass(f, signal);
  std::vector<double> reversed(forward.rbegin(), forward.rend());
  std::vector<double> backward = filter_one_pass(f, reversed);
  return std::vector<double>(backward.rbegin(), backward.rend());
}

}  // namespace flatsos::plugin
