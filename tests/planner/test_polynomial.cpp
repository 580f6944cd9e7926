// Polynomials: evaluation, derivatives (finite-difference twins), integrals, affine changes of
// variable (round trips), Hermite fits (the boundary conditions they were fitted to), minima on
// intervals (known answers).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "flatsos/planner/numerics/polynomial.hpp"

namespace fpl = flatsos::planner;

namespace {
fpl::Polynomial random_polynomial(std::mt19937& rng, int degree) {
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  Eigen::VectorXd c(degree + 1);
  for (auto& v : c) v = u(rng);
  return fpl::Polynomial(c);
}
}  // namespace

TEST(Polynomial, DerivativesMatchFiniteDifferencesAndEachOther) {
  std::mt19937 rng(7);
  for (int degree = 0; degree <= 8; ++degree) {
    const auto p = random_polynomial(rng, degree);
    for (double x : {-1.3, 0.0, 0.4, 2.1}) {
      const double h = 1e-5;
      const double fd = (p(x + h) - p(x - h)) / (2 * h);
      EXPECT_NEAR(p.derivativeAt(x, 1), fd, 1e-7 * (1 + std::abs(fd)));
      for (int order = 0; order <= degree + 1; ++order)
        EXPECT_NEAR(p.derivativeAt(x, order), p.derivative(order)(x), 1e-10 * (1 + std::abs(p.derivative(order)(x))));
    }
  }
}

TEST(Polynomial, IntegralIsTheAntiderivativeDifference) {
  const fpl::Polynomial p(Eigen::Vector3d(1.0, -2.0, 3.0));  // 1 - 2x + 3x^2
  EXPECT_NEAR(p.integral(0.5, 2.0), (2.0 - 4.0 + 8.0) - (0.5 - 0.25 + 0.125), 1e-14);
}

TEST(Polynomial, ComposeAffineRoundTrips) {
  std::mt19937 rng(3);
  for (int degree = 0; degree <= 8; ++degree) {
    const auto p = random_polynomial(rng, degree);
    const auto q = p.composeAffine(0.7, 0.25);
    for (double s : {0.0, 0.3, 1.0}) EXPECT_NEAR(q(s), p(0.7 + 0.25 * s), 1e-12);
    const auto back = q.composeAffine(-0.7 / 0.25, 1.0 / 0.25);
    for (int k = 0; k <= degree; ++k) EXPECT_NEAR(back.coefficients()[k], p.coefficients()[k], 1e-9);
  }
}

TEST(Polynomial, HermiteFitMeetsEveryBoundaryCondition) {
  Eigen::VectorXd d0(4), dT(5);
  d0 << 0.1, 0.001, -0.3, 2.0;
  dT << 1.5708, 0.0, 0.0, 0.0, 0.0;
  const double T = 3.0;
  const auto q = fpl::hermite_interpolant(T, d0, dT);
  EXPECT_EQ(q.degree(), 8);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(q.derivativeAt(0.0, k), d0[k], 1e-12 * (1 + std::abs(d0[k])));
  for (int k = 0; k < 5; ++k) EXPECT_NEAR(q.derivativeAt(T, k), dT[k], 1e-11);
  EXPECT_THROW(fpl::hermite_interpolant(0.0, d0, dT), std::invalid_argument);
  EXPECT_THROW(fpl::hermite_interpolant(1.0, Eigen::Vector2d(std::nan(""), 0), dT), std::invalid_argument);
}

TEST(Polynomial, MinimumOnIntervalKnownAnswers) {
  // (x - 0.3)^2 (x + 1): minimum 0 at 0.3 on [0, 1], not at an end.
  const fpl::Polynomial sq(Eigen::Vector2d(-0.3, 1.0));
  const auto p = sq * sq * fpl::Polynomial(Eigen::Vector2d(1.0, 1.0));
  const auto m = fpl::minimum_on_interval(p, 0.0, 1.0);
  EXPECT_NEAR(m.value, 0.0, 1e-12);
  EXPECT_NEAR(m.at, 0.3, 1e-6);
  // x(1 - x) - 0.1 is negative at the ends, minimum at an endpoint.
  const fpl::Polynomial cap(Eigen::Vector3d(-0.1, 1.0, -1.0));
  EXPECT_NEAR(fpl::minimum_on_interval(cap, 0.0, 1.0).value, -0.1, 1e-15);
  // Brute force agreement on random polynomials.
  std::mt19937 rng(11);
  for (int trial = 0; trial < 50; ++trial) {
    const auto r = random_polynomial(rng, 2 + trial % 7);
    double brute = 1e300;
    for (int i = 0; i <= 20000; ++i) brute = std::min(brute, r(i / 20000.0));
    const double exact = fpl::minimum_on_interval(r, 0.0, 1.0).value;
    EXPECT_LE(exact, brute + 1e-12);
    EXPECT_GE(exact, brute - 1e-6);
  }
}

TEST(Polynomial, RealRootsInInterval) {
  const auto p = fpl::Polynomial(Eigen::Vector2d(-0.2, 1.0)) * fpl::Polynomial(Eigen::Vector2d(-0.7, 1.0)) *
                 fpl::Polynomial(Eigen::Vector3d(1.0, 0.0, 1.0));  // roots 0.2, 0.7, +-i
  const Eigen::VectorXd r = fpl::real_roots_in(p, 0.0, 1.0);
  ASSERT_EQ(r.size(), 2);
  EXPECT_NEAR(r[0], 0.2, 1e-12);
  EXPECT_NEAR(r[1], 0.7, 1e-12);
}
