#pragma once
// Third-order Butterworth low-pass filter, digitised by the bilinear transform with the cutoff
// pre-warped (so the digital gain at the cutoff is exactly 1/sqrt(2)), applied forward and then
// backward for zero phase: the combined gain is |H|^2, 1/2 at the cutoff. This is the filter
// OpenSim's tools apply to coordinate data (Signal::LowpassIIR), including its start-up: each
// pass copies its first three input samples to the output and runs the recursion from the
// fourth, so callers pad the signal first (motion_processing.hpp) to keep that transient away
// from the data. Butterworth, Wireless Engineer 7:536-541, 1930; bilinear transform with
// pre-warping: Oppenheim & Schafer, Discrete-Time Signal Processing, section 7.1.

#include <array>
#include <vector>

namespace flatsos::plugin {

/// y[i] = sum_k numerator[k] x[i-k] - sum_{k>=1} denominator[k] y[i-k], denominator[0] = 1.
struct ThirdOrderFilterCoefficients {
  std::array<double, 4> numerator{};
  std::array<double, 4> denominator{};
};

/// Coefficients for cutoff_hz at the sample interval; throws std::invalid_argument unless
/// 0 < cutoff_hz < 1 / (2 sample_interval_s) (OpenSim silently lowers such a cutoff to 0.49 of the
/// sample rate; here it is an error).
ThirdOrderFilterCoefficients third_order_butterworth_lowpass(double cutoff_hz, double sample_interval_s);

/// One causal pass with OpenSim's start-up (outputs 0..2 = inputs 0..2). Needs >= 4 samples.
std::vector<double> filter_one_pass(const ThirdOrderFilterCoefficients& filter, const std::vector<double>& signal);

/// Forward pass, then a pass over the reversed result, reversed back (OpenSim's LowpassIIR).
/// Throws std::invalid_argument for fewer than 4 samples, a non-finite sample or a bad cutoff.
std::vector<double> lowpass_forward_backward(const std::vector<double>& signal, double cutoff_hz,
                                             double sample_interval_s);

}  // namespace flatsos::plugin
