// TimeJet carries (f, f', f'') through the operations the pin-tree dynamics uses. Checked
// against two independent computations: nested dual numbers with both infinitesimals on the same
// curve, and central differences in time of the plain double-precision expression.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "flatsos/plugin/model/dual_number.hpp"

namespace fp = flatsos::plugin;

namespace {

// An expression with every operation TimeJet has: +, -, *, /, unary -, sin, cos, constants.
template <class S>
S expression(const S& a, const S& b, const S& c) {
  using std::cos;
  using std::sin;
  S out = sin(a) * b / (S(3.0) + cos(c)) - a * b * c + (-a) / (S(2.0) + b * b);
  out += cos(a * c) * S(0.5);
  out -= b;
  out *= S(1.5) + sin(b);
  out /= S(2.5) + c * c;
  return out;
}

struct Curve {
  double x, rate, acceleration;
  double at(double t) const { return x + rate * t + 0.5 * acceleration * t * t; }
};

}  // namespace

TEST(TimeJet, CarriesTheFirstTwoTimeDerivativesThroughArithmetic) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> value(-1.5, 1.5), rate(-4.0, 4.0);
  for (int trial = 0; trial < 50; ++trial) {
    const Curve a{value(rng), rate(rng), rate(rng)}, b{value(rng), rate(rng), rate(rng)}, c{value(rng), rate(rng), rate(rng)};
    using J = fp::TimeJet<double>;
    const J f = expression(J(a.x, a.rate, a.acceleration), J(b.x, b.rate, b.acceleration), J(c.x, c.rate, c.acceleration));

    // Nested duals: x + e1 x' + e2 x' + e1 e2 x''; the e1 e2 coefficient is the second derivative.
    using H = fp::Dual<fp::Dual<double>>;
    auto nested = [](const Curve& x) { return H(fp::Dual<double>(x.x, x.rate), fp::Dual<double>(x.rate, x.acceleration)); };
    const H g = expression(nested(a), nested(b), nested(c));
    const double scale = 1.0 + std::abs(f.value) + std::abs(f.rate) + std::abs(f.acceleration);
    EXPECT_NEAR(f.value, g.value.value, 1e-14 * scale);
    EXPECT_NEAR(f.rate, g.derivative.value, 1e-13 * scale);
    EXPECT_NEAR(f.rate, g.value.derivative, 1e-13 * scale);
    EXPECT_NEAR(f.acceleration, g.derivative.derivative, 1e-12 * scale);

    // Central differences in time along the curves (fourth order, step 1e-3).
    auto plain = [&](double t) { return expression(a.at(t), b.at(t), c.at(t)); };
    const double h = 1e-3;
    const double m2 = plain(-2 * h), m1 = plain(-h), z = plain(0.0), p1 = plain(h), p2 = plain(2 * h);
    EXPECT_NEAR(f.value, z, 1e-14 * scale);
    EXPECT_NEAR(f.rate, (m2 - 8.0 * m1 + 8.0 * p1 - p2) / (12.0 * h), 1e-8 * scale);
    EXPECT_NEAR(f.acceleration, (-m2 + 16.0 * m1 - 30.0 * z + 16.0 * p1 - p2) / (12.0 * h * h), 1e-5 * scale);
    EXPECT_EQ(fp::primal(f), f.value);
  }
}

TEST(TimeJet, WithDualNumbersInsideGivesTheJetsDerivativeInAParameter) {
  // d/dp of (f, f', f'') where the curve of a starts at p: the dual parts against differences in p.
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> value(-1.5, 1.5), rate(-4.0, 4.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Curve a{value(rng), rate(rng), rate(rng)}, b{value(rng), rate(rng), rate(rng)}, c{value(rng), rate(rng), rate(rng)};
    using D = fp::Dual<double>;
    using J = fp::TimeJet<D>;
    auto jet_of = [](const Curve& x, double seed) { return J(D(x.x, seed), D(x.rate), D(x.acceleration)); };
    const J f = expression(jet_of(a, 1.0), jet_of(b, 0.0), jet_of(c, 0.0));
    auto plain_jet = [&](double shift) {
      using P = fp::TimeJet<double>;
      return expression(P(a.x + shift, a.rate, a.acceleration), P(b.x, b.rate, b.acceleration), P(c.x, c.rate, c.acceleration));
    };
    const double h = 1e-6;
    const auto up = plain_jet(h), down = plain_jet(-h);
    const double scale = 1.0 + std::abs(f.value.derivative) + std::abs(f.rate.derivative) + std::abs(f.acceleration.derivative);
    EXPECT_NEAR(f.value.derivative, (up.value - down.value) / (2 * h), 1e-7 * scale);
    EXPECT_NEAR(f.rate.derivative, (up.rate - down.rate) / (2 * h), 1e-7 * scale);
    EXPECT_NEAR(f.acceleration.derivative, (up.acceleration - down.acceleration) / (2 * h), 1e-6 * scale);
  }
}
