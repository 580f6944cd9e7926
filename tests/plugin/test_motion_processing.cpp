// Motion processing as OpenSim's InverseDynamicsTool does it: the Butterworth filter's response,
// the natural quintic spline's defining properties (and agreement with Simbody's GCVSPL, the
// code OpenSim calls), padding, the uniform grid, and the whole chain on a synthetic table.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there

#include <cmath>
#include <complex>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "flatsos/plugin/io/butterworth_filter.hpp"
#include "flatsos/plugin/io/motion_processing.hpp"
#include "flatsos/plugin/io/natural_quintic_spline.hpp"

#include <SimTKmath.h>

namespace {

using namespace flatsos::plugin;

std::complex<double> response(const ThirdOrderFilterCoefficients& f, double frequency_hz, double T) {
  const std::complex<double> z_inv = std::polar(1.0, -2.0 * M_PI * frequency_hz * T);
  std::complex<double> num = 0.0, den = 0.0, power = 1.0;
  for (int k = 0; k < 4; ++k, power *= z_inv) {
    num += f.numerator[static_cast<std::size_t>(k)] * power;
    den += f.denominator[static_cast<std::size_t>(k)] * power;
  }
  return num / den;
}

TEST(Butterworth, GainIsOneAtDcAndOneOverRootTwoAtTheCutoff) {
  const double T = 1.0 / 120.0, fc = 6.0;
  const auto f = third_order_butterworth_lowpass(fc, T);
  EXPECT_NEAR(std::abs(response(f, 0.0, T)), 1.0, 1e-14);
  EXPECT_NEAR(std::abs(response(f, fc, T)), 1.0 / std::sqrt(2.0), 1e-14);
  EXPECT_NEAR(std::abs(response(f, 0.5 / T, T)), 0.0, 1e-14);  // triple zero at Nyquist
}

TEST(Butterworth, MagnitudeFollowsTheWarpedButterworthLaw) {
  // Bilinear transform of a Butterworth: |H|^2 = 1 / (1 + (tan(pi f T) / tan(pi fc T))^6).
  const double T = 0.004, fc = 11.0;
  const auto f = third_order_butterworth_lowpass(fc, T);
  for (double freq : {0.5, 3.0, 9.0, 11.0, 14.0, 40.0, 90.0, 120.0}) {
    const double ratio = std::tan(M_PI * freq * T) / std::tan(M_PI * fc * T);
    EXPECT_NEAR(std::norm(response(f, freq, T)), 1.0 / (1.0 + std::pow(ratio, 6)), 1e-13) << freq;
  }
}

std::vector<double> sampled_sine(double frequency_hz, double T, int n) {
  std::vector<double> s(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) s[static_cast<std::size_t>(i)] = std::sin(2.0 * M_PI * frequency_hz * i * T + 0.3);
  return s;
}

TEST(Butterworth, ForwardBackwardHalvesASineAtTheCutoffWithoutPhaseShift) {
  const double T = 1.0 / 120.0, fc = 6.0;
  for (double freq : {fc, 2.0 * fc}) {
    const auto x = sampled_sine(freq, T, 4000);
    const auto y = lowpass_forward_backward(x, fc, T);
    const double ratio = std::tan(M_PI * freq * T) / std::tan(M_PI * fc * T);
    const double gain = 1.0 / (1.0 + std::pow(ratio, 6));  // |H|^2, real: zero phase
    for (std::size_t i = 1000; i < 3000; ++i) ASSERT_NEAR(y[i], gain * x[i], 1e-9) << freq << " Hz, i " << i;
  }
}

TEST(Butterworth, EachPassStartsFromItsFirstThreeInputs) {
  const auto f = third_order_butterworth_lowpass(6.0, 1.0 / 120.0);
  const std::vector<double> x = {0.3, -1.0, 2.0, 5.0, 4.0, 1.0};
  const auto y = filter_one_pass(f, x);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(y[i], x[i]);
  EXPECT_NEAR(y[3], f.numerator[0] * 5.0 + f.numerator[1] * 2.0 + f.numerator[2] * -1.0 + f.numerator[3] * 0.3 -
                        f.denominator[1] * 2.0 - f.denominator[2] * -1.0 - f.denominator[3] * 0.3,
              1e-15);
}

TEST(Butterworth, ConstantPassesUnchanged) {
  const auto y = lowpass_forward_backward(std::vector<double>(50, 2.5), 6.0, 0.01);
  for (double v : y) EXPECT_NEAR(v, 2.5, 1e-13);
}

TEST(Butterworth, RejectsBadInput) {
  EXPECT_THROW(third_order_butterworth_lowpass(60.0, 1.0 / 120.0), std::invalid_argument);  // at Nyquist
  EXPECT_THROW(third_order_butterworth_lowpass(0.0, 0.01), std::invalid_argument);
  EXPECT_THROW(third_order_butterworth_lowpass(6.0, -0.01), std::invalid_argument);
  EXPECT_THROW(lowpass_forward_backward({1.0, 2.0, 3.0}, 6.0, 0.01), std::invalid_argument);
  EXPECT_THROW(lowpass_forward_backward({1.0, 2.0, NAN, 3.0, 4.0}, 6.0, 0.01), std::invalid_argument);
}

std::vector<double> uneven_knots(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> step(0.05, 0.15);
  std::vector<double> x = {-0.4};
  for (int i = 1; i < n; ++i) x.push_back(x.back() + step(rng));
  return x;
}

std::vector<double> noisy_values(const std::vector<double>& x, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.2);
  std::vector<double> y;
  for (double xi : x) y.push_back(std::sin(3.0 * xi) + noise(rng));
  return y;
}

TEST(NaturalQuinticSpline, InterpolatesTheKnots) {
  const auto x = uneven_knots(30, 1);
  const auto y = noisy_values(x, 2);
  const NaturalQuinticSpline s(x, y);
  for (std::size_t i = 0; i < x.size(); ++i) EXPECT_NEAR(s.value(x[i]), y[i], 1e-12) << i;
}

TEST(NaturalQuinticSpline, ThirdAndFourthDerivativesVanishAtBothEnds) {
  const auto x = uneven_knots(25, 3);
  const NaturalQuinticSpline s(x, noisy_values(x, 4));
  for (double end : {x.front(), x.back()}) {
    EXPECT_NEAR(s.derivative(end, 3), 0.0, 1e-7);
    EXPECT_NEAR(s.derivative(end, 4), 0.0, 1e-5);
  }
  EXPECT_GT(std::abs(s.derivative(x.front(), 2)), 1e-3);  // the conditions stop at the third
}

TEST(NaturalQuinticSpline, DerivativesUpToTheFourthAreContinuousAtInteriorKnots) {
  const auto x = uneven_knots(20, 5);
  const NaturalQuinticSpline s(x, noisy_values(x, 6));
  for (std::size_t i = 1; i + 1 < x.size(); ++i) {
    const double left = std::nextafter(x[i], -INFINITY);
    for (int order = 0; order <= 4; ++order) {
      const double scale = std::pow(10.0, order);
      EXPECT_NEAR(s.derivative(left, order), s.derivative(x[i], order), 1e-9 * scale) << i << " order " << order;
    }
  }
}

TEST(NaturalQuinticSpline, ReproducesQuadraticsExactly) {
  const auto x = uneven_knots(15, 7);
  std::vector<double> y;
  for (double xi : x) y.push_back(1.5 - 2.0 * xi + 0.75 * xi * xi);
  const NaturalQuinticSpline s(x, y);
  for (double t = x.front(); t <= x.back(); t += 0.0137) {
    EXPECT_NEAR(s.value(t), 1.5 - 2.0 * t + 0.75 * t * t, 1e-12);
    EXPECT_NEAR(s.firstDerivative(t), -2.0 + 1.5 * t, 1e-10);
    EXPECT_NEAR(s.secondDerivative(t), 1.5, 1e-8);
  }
}

TEST(NaturalQuinticSpline, DoesNotReproduceACubic) {
  // A cubic has f''' = 6 everywhere, so the natural end conditions cannot hold for it.
  const auto x = uneven_knots(15, 8);
  std::vector<double> y;
  for (double xi : x) y.push_back(xi * xi * xi);
  const NaturalQuinticSpline s(x, y);
  EXPECT_NEAR(s.derivative(x.front(), 3), 0.0, 1e-7);
  const double mid = 0.5 * (x.front() + x[1]);
  EXPECT_GT(std::abs(s.secondDerivative(x.front()) - 6.0 * x.front()), 1e-3);
  EXPECT_GT(std::abs(s.value(mid) - mid * mid * mid), 1e-7);
}

TEST(NaturalQuinticSpline, DerivativesMatchFiniteDifferences) {
  const auto x = uneven_knots(30, 9);
  const NaturalQuinticSpline s(x, noisy_values(x, 10));
  const double h = 1e-5;
  for (double t = x.front() + 0.01; t < x.back() - 0.01; t += 0.0731) {
    EXPECT_NEAR(s.firstDerivative(t), (s.value(t + h) - s.value(t - h)) / (2 * h), 1e-5 * (1 + std::abs(s.firstDerivative(t))));
    EXPECT_NEAR(s.secondDerivative(t), (s.firstDerivative(t + h) - s.firstDerivative(t - h)) / (2 * h),
                1e-5 * (1 + std::abs(s.secondDerivative(t))));
  }
}

TEST(NaturalQuinticSpline, AgreesWithSimbodysGcvsplAtZeroErrorVariance) {
  // OpenSim's GCVSpline fits with SimTK::SplineFitter::fitFromErrorVariance(degree, x, y, 0).
  const auto x = uneven_knots(40, 11);
  const auto y = noisy_values(x, 12);
  const NaturalQuinticSpline ours(x, y);
  SimTK::Vector sx(static_cast<int>(x.size())), sy(static_cast<int>(y.size()));
  for (int i = 0; i < sx.size(); ++i) sx[i] = x[static_cast<std::size_t>(i)], sy[i] = y[static_cast<std::size_t>(i)];
  const SimTK::Spline theirs = SimTK::SplineFitter<SimTK::Real>::fitFromErrorVariance(5, sx, sy, 0.0).getSpline();
  for (double t = x.front(); t <= x.back(); t += 0.0173) {
    const SimTK::Vector at(1, t);
    EXPECT_NEAR(ours.value(t), theirs.calcValue(at), 1e-10);
    EXPECT_NEAR(ours.firstDerivative(t), theirs.calcDerivative(std::vector<int>{0}, at), 1e-8);
    EXPECT_NEAR(ours.secondDerivative(t), theirs.calcDerivative(std::vector<int>{0, 0}, at), 1e-6);
  }
}

TEST(NaturalQuinticSpline, RejectsBadKnots) {
  EXPECT_THROW(NaturalQuinticSpline({0, 1, 2, 3, 4}, {0, 1, 2, 3, 4}), std::invalid_argument);
  EXPECT_THROW(NaturalQuinticSpline({0, 1, 2, 2, 4, 5}, {0, 1, 2, 3, 4, 5}), std::invalid_argument);
  EXPECT_THROW(NaturalQuinticSpline({0, 1, 2, 3, 4, 5}, {0, 1, NAN, 3, 4, 5}), std::invalid_argument);
  const NaturalQuinticSpline s({0, 1, 2, 3, 4, 5}, {0, 1, 0, 1, 0, 1});
  EXPECT_THROW(s.value(5.5), std::invalid_argument);
  EXPECT_THROW(s.derivative(1.0, 6), std::invalid_argument);
}

TEST(MotionPadding, RoundTripAndPointSymmetryAboutTheEnds) {
  const std::vector<double> s = {0.2, 0.9, -0.4, 1.7, 3.0, 2.2, 0.1};
  const int pad = 4;
  const auto p = pad_by_point_reflection(s, pad);
  ASSERT_EQ(p.size(), s.size() + 2 * pad);
  EXPECT_EQ(std::vector<double>(p.begin() + pad, p.end() - pad), s);
  for (int k = 1; k <= pad; ++k) {
    EXPECT_NEAR(p[pad - k] + p[pad + k], 2.0 * s.front(), 1e-14);
    const std::size_t last = pad + s.size() - 1;
    EXPECT_NEAR(p[last + k] + p[last - k], 2.0 * s.back(), 1e-14);
  }
}

TEST(MotionPadding, ExtendsAStraightLineAsTheSameLine) {
  std::vector<double> s;
  for (int i = 0; i < 9; ++i) s.push_back(0.5 + 0.25 * i);
  const auto p = pad_by_point_reflection(s, 8);
  for (std::size_t i = 0; i < p.size(); ++i) EXPECT_DOUBLE_EQ(p[i], 0.5 + 0.25 * (static_cast<double>(i) - 8.0));
  EXPECT_THROW(pad_by_point_reflection(s, 9), std::invalid_argument);
  EXPECT_THROW(pad_by_point_reflection(s, -1), std::invalid_argument);
}

TEST(MotionGrid, StepsAreAddedRepeatedlyAndTheReportRangeEndsAtOrBeforeEachBound) {
  const auto grid = uniform_time_grid(-0.5, 1.5, 0.1);
  ASSERT_EQ(grid.size(), 20u);  // 0.1 added 19 times is 1.4000000000000004, 20 times > 1.5
  double t = -0.5;
  for (double g : grid) {
    EXPECT_EQ(g, t);  // bit for bit: the same additions
    t += 0.1;
  }
  const auto [first, last] = report_sample_range(grid, 0.0, 1.0);
  EXPECT_LE(grid[first], 0.0);
  EXPECT_GT(grid[first + 1], 0.0);
  EXPECT_LE(grid[last], 1.0);
  EXPECT_GT(grid[last + 1], 1.0);
}

}  // namespace
