// The exchange's rows: a constraint violated at its minimum gets a point there; violated again at
// a point the LP already imposes (it met the row only to its own precision), that point gets the
// full margin and twice the violation as extra margin in the rows the next LP sees.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "flatsos/planner/numerics/polynomial.hpp"
#include "sos/sos_setup.hpp"

namespace fpl = flatsos::planner;

TEST(ExchangeRows, AViolationAtAnImposedPointRaisesThatPointsMargin) {
  fpl::detail::SosSetup setup(1.0, fpl::BSplineBasis(4, 1, 1.0));
  setup.free_coefficients = 1;
  fpl::detail::ConstraintPolynomial c;
  // g(s; theta) = (s - 0.5)^2 - 1e-6 + theta s: for theta = 0 its minimum, -1e-6, is at s = 0.5.
  c.base = Eigen::Vector3d(0.25 - 1e-6, -1.0, 1.0);
  c.G = Eigen::Vector3d(0.0, 1.0, 0.0);
  c.points = {0.0, 1.0};
  c.sticky = {false, false};
  setup.constraints.push_back(c);
  const Eigen::VectorXd theta = Eigen::VectorXd::Zero(1);
  double min_value = 0.0;

  ASSERT_TRUE(fpl::detail::add_violated_points(setup, theta, 1e-9, min_value));
  EXPECT_NEAR(min_value, -1e-6, 1e-15);
  const fpl::detail::ConstraintPolynomial& after = setup.constraints[0];
  ASSERT_EQ(after.points.size(), 3u);
  EXPECT_NEAR(after.points[2], 0.5, 1e-12);
  EXPECT_TRUE(after.extra_margin.empty());

  // The same theta again: the minimum sits on the imposed point.
  ASSERT_TRUE(fpl::detail::add_violated_points(setup, theta, 1e-9, min_value));
  ASSERT_EQ(after.points.size(), 3u);
  ASSERT_EQ(after.extra_margin.size(), 1u);
  EXPECT_EQ(after.extra_margin[0].first, after.points[2]);
  EXPECT_NEAR(after.extra_margin[0].second, 1e-9 + 2e-6, 1e-15);
  fpl::detail::build_exchange_rows(setup, 1e-9);
  // Row 2 (s = 0.5): >= margin + extra - g's base at s, i.e. theta/2 >= 1e-9 + (1e-9 + 2e-6) + 1e-6.
  EXPECT_NEAR(setup.lp.row_lower[2], 1e-9 + 1e-9 + 2e-6 + 1e-6, 1e-15);
  EXPECT_NEAR(setup.lp.row_lower[0], 1e-9 - (0.25 - 1e-6), 1e-15);  // the others as before

  // Met (theta = 1e-5 lifts g near s = 0.5 above zero): nothing added.
  ASSERT_FALSE(fpl::detail::add_violated_points(setup, Eigen::VectorXd::Constant(1, 1e-5), 1e-9, min_value));
  EXPECT_EQ(after.extra_margin.size(), 1u);
}

TEST(ExchangeRows, AShallowNewViolationIsImposedWithItsDepthAsMargin) {
  // g(s; theta) = (s - 0.5)^2 - depth + theta s, violated by `depth` at s = 0.5 for theta = 0.
  auto setup_with = [](double depth) {
    fpl::detail::SosSetup setup(1.0, fpl::BSplineBasis(4, 1, 1.0));
    setup.free_coefficients = 1;
    fpl::detail::ConstraintPolynomial c;
    c.base = Eigen::Vector3d(0.25 - depth, -1.0, 1.0);
    c.G = Eigen::Vector3d(0.0, 1.0, 0.0);
    c.points = {0.0, 1.0};
    c.sticky = {false, false};
    setup.constraints.push_back(c);
    return setup;
  };
  const Eigen::VectorXd theta = Eigen::VectorXd::Zero(1);
  double min_value = 0.0;
  // Within the lift: the new point's row asks for the depth on top of the margin.
  auto shallow = setup_with(1e-4);
  ASSERT_TRUE(fpl::detail::add_violated_points(shallow, theta, 1e-9, min_value, 1e-9, 1e-3));
  const auto& lifted = shallow.constraints[0];
  ASSERT_EQ(lifted.points.size(), 3u);
  ASSERT_EQ(lifted.extra_margin.size(), 1u);
  EXPECT_EQ(lifted.extra_margin[0].first, lifted.points[2]);
  EXPECT_NEAR(lifted.extra_margin[0].second, 1e-4, 1e-15);
  fpl::detail::build_exchange_rows(shallow, 1e-9);
  // Row 2 (s = 0.5): theta/2 >= 1e-9 + 1e-4 - (0.25 - 1e-4 - 0.5 + 0.25) = 1e-9 + 2e-4.
  EXPECT_NEAR(shallow.lp.row_lower[2], 1e-9 + 2e-4, 1e-15);
  // Deeper than the lift, or without one: the point alone, as in the reserves-only exchange.
  for (const double lift : {1e-5, 0.0}) {
    auto plain = setup_with(1e-4);
    ASSERT_TRUE(fpl::detail::add_violated_points(plain, theta, 1e-9, min_value, 1e-9, lift));
    EXPECT_EQ(plain.constraints[0].points.size(), 3u);
    EXPECT_TRUE(plain.constraints[0].extra_margin.empty()) << "lift " << lift;
  }
}

TEST(ExchangeRows, TheScreenedSearchAddsWhatEverySegmentsExactMinimumAdds) {
  // add_violated_points finds exact minima only where a segment's least Bernstein coefficient
  // could be a violation or a new least value. Against the exact minimum of every segment: the
  // same points, the same least value. The segments: violated ones of many depths, near-active
  // ones, far ones, and ones whose Bernstein coefficients go negative while the polynomial stays
  // positive ((s - r)^2 + small: the bound is no proof of a violation).
  std::mt19937 rng(35);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  fpl::detail::SosSetup setup(1.0, fpl::BSplineBasis(4, 1, 1.0));
  setup.free_coefficients = 1;
  const double offsets[] = {-1.0, -0.3, -1e-2, -1e-4, -1e-7, 1e-9, 1e-6, 1e-3, 0.5, 10.0, 300.0};
  for (int k = 0; k < 220; ++k) {
    // p(s) = a (s - r)^2 + b (s - r)^4 + offset, a quartic in monomials of s.
    const double a = 0.1 + 5.0 * unit(rng), b = 3.0 * unit(rng), r = unit(rng), offset = offsets[k % 11];
    Eigen::VectorXd m = Eigen::VectorXd::Zero(5);
    m[0] = a * r * r + b * std::pow(r, 4) + offset;
    m[1] = -2.0 * a * r - 4.0 * b * std::pow(r, 3);
    m[2] = a + 6.0 * b * r * r;
    m[3] = -4.0 * b * r;
    m[4] = b;
    fpl::detail::ConstraintPolynomial c;
    c.base = m;
    c.G = Eigen::VectorXd::Zero(5);
    c.points = {0.0, 1.0};
    c.sticky = {false, false};
    setup.constraints.push_back(c);
  }
  const Eigen::VectorXd theta = Eigen::VectorXd::Zero(1);
  constexpr double kTolerance = 1e-9;
  double expected_min = 1e300;
  std::vector<std::vector<double>> expected_points;
  for (const auto& c : setup.constraints) {
    const fpl::IntervalMinimum mn = fpl::minimum_on_interval(c.at(theta), 0.0, 1.0);
    expected_min = std::min(expected_min, mn.value);
    std::vector<double> points = c.points;
    if (mn.value < -kTolerance) points.push_back(mn.at);
    expected_points.push_back(points);
  }
  double min_value = 0.0;
  ASSERT_TRUE(fpl::detail::add_violated_points(setup, theta, 1e-9, min_value, kTolerance, 0.0));
  EXPECT_EQ(min_value, expected_min);
  int added = 0;
  for (std::size_t k = 0; k < setup.constraints.size(); ++k) {
    EXPECT_EQ(setup.constraints[k].points, expected_points[k]) << "segment " << k;
    added += static_cast<int>(setup.constraints[k].points.size()) - 2;
  }
  EXPECT_EQ(added, 100);  // the five violated depths, 20 segments each

  // Nothing violated: the least value is still the least exact minimum, also where it belongs to
  // a segment whose Bernstein bound (1e-6, at s = 0) is above another's ((s - 0.5)^2 + 1e-3: -0.25).
  fpl::detail::SosSetup met(1.0, fpl::BSplineBasis(4, 1, 1.0));
  met.free_coefficients = 1;
  for (const Eigen::Vector3d& m : {Eigen::Vector3d(0.25 + 1e-3, -1.0, 1.0), Eigen::Vector3d(1e-6, 1.0, 0.0)}) {
    fpl::detail::ConstraintPolynomial c;
    c.base = m;
    c.G = Eigen::Vector3d::Zero();
    c.points = {0.0, 1.0};
    c.sticky = {false, false};
    met.constraints.push_back(c);
  }
  ASSERT_FALSE(fpl::detail::add_violated_points(met, theta, 1e-9, min_value, kTolerance, 0.0));
  EXPECT_NEAR(min_value, 1e-6, 1e-18);
}
