#pragma once
// The finite-difference twin of an analytic derivative, with the error the difference itself can
// have, so that tests compare against a tolerance that follows from the step instead of a
// hand-picked constant.
//
// D(h) = (f(x + h) - f(x - h)) / 2h = f'(x) + c h^2 + O(h^4), so D(2h) - D(h) = 3 c h^2: the
// truncation error of D(h) is estimated as |D(2h) - D(h)| / 3 from the data. Round-off: each f
// value carries about eps |f|, and x + h itself is rounded by about eps |x| (a relative error of
// eps |x| / h in the step, hence in D); both are divided by h. The tolerance is kSafety times the
// sum of truncation and round-off.
// Near a kink of f (within 2h) the estimate grows accordingly: keep sample points away from kinks.
#include <algorithm>
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace flatsos::test {

struct FiniteDifference {
  double estimate = 0.0;   ///< D(h)
  double tolerance = 0.0;  ///< how far the true derivative may be from it
};

/// A step for x on the scale `scale` (the size of x's typical values): cbrt(eps) max(|x|, scale),
/// which balances truncation (h^2) and round-off (eps / h).
inline double default_step(double x, double scale) {
  return std::cbrt(std::numeric_limits<double>::epsilon()) * std::max(std::abs(x), scale);
}

template <class F>
FiniteDifference central_difference(F f, double x, double h) {
  constexpr double kSafety = 10.0;
  const double f1p = f(x + h), f1m = f(x - h), f2p = f(x + 2 * h), f2m = f(x - 2 * h);
  const double d1 = (f1p - f1m) / (2 * h), d2 = (f2p - f2m) / (4 * h);
  const double truncation = std::abs(d2 - d1) / 3.0;
  const double size = std::max({std::abs(f1p), std::abs(f1m), std::abs(f2p), std::abs(f2m), std::abs(f(x))});
  const double roundoff = std::numeric_limits<double>::epsilon() * (size + std::abs(x) * std::abs(d1)) / h;
  return {d1, kSafety * (truncation + roundoff)};
}

}  // namespace flatsos::test

/// EXPECT that an analytic derivative equals its finite-difference twin within the twin's error.
#define EXPECT_MATCHES_FINITE_DIFFERENCE(analytic, twin) \
  EXPECT_NEAR((analytic), (twin).estimate, (twin).tolerance)
