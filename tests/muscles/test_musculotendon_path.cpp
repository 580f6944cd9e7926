// Muscle paths as polynomials of the joint angles: OpenSim's term order, values against an
// independent evaluation (std::pow over the term table), partial derivatives and moment arms
// against finite differences, time derivatives along a joint motion against finite differences
// in time (each order against the one below), constant moment arms as the order-1 case, held
// coordinates, and bad input named.
#include <gtest/gtest.h>

#include "finite_difference.hpp"

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "flatsos/muscles/length_polynomial.hpp"
#include "flatsos/muscles/musculotendon_path.hpp"

namespace fm = flatsos::muscles;
using flatsos::test::central_difference;
using flatsos::test::default_step;

namespace {

std::vector<double> random_coefficients(int dimension, int order, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  std::vector<double> c(static_cast<std::size_t>(fm::LengthPolynomial::termCount(dimension, order)));
  for (double& v : c) v = u(rng);
  c[0] = 0.3;
  return c;
}

// The sum and the sum of the terms' magnitudes: two evaluations in different orders may differ
// by a few roundings of the largest partial sums, so the comparison is relative to the magnitude,
// not to the (possibly cancelled) value.
struct Evaluation {
  double value = 0.0;
  double magnitude = 0.0;
};

Evaluation independent_value(const std::vector<double>& c, int dimension, int order, const std::vector<double>& x) {
  const auto e = fm::LengthPolynomial::termExponents(dimension, order);
  Evaluation sum;
  for (std::size_t t = 0; t < c.size(); ++t) {
    double term = c[t];
    for (int k = 0; k < dimension; ++k) term *= std::pow(x[k], e[t][k]);
    sum.value += term;
    sum.magnitude += std::abs(term);
  }
  return sum;
}

// A joint motion q_i(t) = sum_k a_ik t^k (degree 5) and its derivatives 0..4 at t, laid out as
// the jets expect: out[j * n + i] = d^j q_i / dt^j.
struct JointMotion {
  std::vector<std::vector<double>> a;  // per joint, 6 coefficients
  std::vector<double> jet(double t, int count) const {
    const int n = static_cast<int>(a.size());
    std::vector<double> out(static_cast<std::size_t>(n * count), 0.0);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < count; ++j)
        for (int k = j; k < 6; ++k) {
          double falling = 1.0;
          for (int f = 0; f < j; ++f) falling *= k - f;
          out[j * n + i] += a[i][k] * falling * std::pow(t, k - j);
        }
    return out;
  }
};

JointMotion random_motion(int joints, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  JointMotion m;
  for (int i = 0; i < joints; ++i) {
    std::vector<double> c(6);
    for (double& v : c) v = u(rng);
    m.a.push_back(c);
  }
  return m;
}

}  // namespace

TEST(LengthPolynomial, TermsRunInOpenSimsOrder) {
  // OpenSim's MultivariatePolynomialFunction documents this table for (X, Y, Z), order 3.
  const std::vector<std::vector<int>> opensim = {
      {0, 0, 0}, {0, 0, 1}, {0, 0, 2}, {0, 0, 3}, {0, 1, 0}, {0, 1, 1}, {0, 1, 2}, {0, 2, 0}, {0, 2, 1}, {0, 3, 0},
      {1, 0, 0}, {1, 0, 1}, {1, 0, 2}, {1, 1, 0}, {1, 1, 1}, {1, 2, 0}, {2, 0, 0}, {2, 0, 1}, {2, 1, 0}, {3, 0, 0}};
  EXPECT_EQ(fm::LengthPolynomial::termExponents(3, 3), opensim);
  EXPECT_EQ(fm::LengthPolynomial::termCount(3, 3), 20);
  for (int d = 0; d <= 6; ++d)
    for (int o = 0; o <= 6; ++o)
      EXPECT_EQ(static_cast<long>(fm::LengthPolynomial::termExponents(d, o).size()), fm::LengthPolynomial::termCount(d, o));
  // Coefficient 6 is Y Z^2.
  std::vector<double> c(20, 0.0);
  c[6] = 1.0;
  const fm::LengthPolynomial p(3, 3, c);
  const double x[3] = {0.7, 2.0, 3.0};
  EXPECT_DOUBLE_EQ(p.value(x), 2.0 * 9.0);
}

TEST(LengthPolynomial, ValuesMatchAnIndependentEvaluation) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int d = 0; d <= 4; ++d)
    for (int o = 0; o <= 5; ++o) {
      const auto c = random_coefficients(d, o, static_cast<unsigned>(10 * d + o));
      const fm::LengthPolynomial p(d, o, c);
      for (int s = 0; s < 5; ++s) {
        std::vector<double> x(static_cast<std::size_t>(d));
        for (double& v : x) v = u(rng);
        // Repeated products and std::pow round each term differently (up to order + 1 roundings),
        // and so each partial sum: at most about 2 (terms + order) eps of the magnitude apart. A
        // term in the wrong place is off by a whole term.
        const Evaluation reference = independent_value(c, d, o, x);
        const double rounding = 2.0 * (static_cast<double>(c.size()) + o) * 2.2e-16 * reference.magnitude;
        EXPECT_NEAR(p.value(x.data()), reference.value, rounding) << "d " << d << " o " << o;
      }
    }
}

TEST(LengthPolynomial, HoldingAnArgumentSubstitutesItsValue) {
  // The polynomial of the other arguments equals the whole one with the held argument in place,
  // for every argument of every dimension and order (an independent evaluation as the measure of
  // rounding); holding every argument in turn leaves the value.
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int d = 1; d <= 4; ++d)
    for (int o = 0; o <= 5; ++o) {
      const auto c = random_coefficients(d, o, static_cast<unsigned>(100 + 10 * d + o));
      const fm::LengthPolynomial p(d, o, c);
      for (int k = 0; k < d; ++k) {
        std::vector<double> x(static_cast<std::size_t>(d));
        for (double& v : x) v = u(rng);
        const fm::LengthPolynomial held = p.withArgumentHeld(k, x[static_cast<std::size_t>(k)]);
        EXPECT_EQ(held.dimension(), d - 1);
        EXPECT_EQ(held.order(), o);
        std::vector<double> rest = x;
        rest.erase(rest.begin() + k);
        const Evaluation reference = independent_value(c, d, o, x);
        const double rounding = 4.0 * (static_cast<double>(c.size()) + o) * 2.2e-16 * reference.magnitude;
        EXPECT_NEAR(held.value(rest.data()), reference.value, rounding) << "d " << d << " o " << o << " k " << k;
      }
      std::vector<double> x(static_cast<std::size_t>(d));
      for (double& v : x) v = u(rng);
      fm::LengthPolynomial all = p;
      for (int k = d - 1; k >= 0; --k) all = all.withArgumentHeld(k, x[static_cast<std::size_t>(k)]);
      EXPECT_EQ(all.dimension(), 0);
      EXPECT_NEAR(all.value(nullptr), independent_value(c, d, o, x).value, 1e-13) << "d " << d << " o " << o;
    }
  const fm::LengthPolynomial p(2, 2, random_coefficients(2, 2, 1));
  EXPECT_THROW(p.withArgumentHeld(2, 0.0), std::invalid_argument);
  EXPECT_THROW(p.withArgumentHeld(-1, 0.0), std::invalid_argument);
  EXPECT_THROW(p.withArgumentHeld(0, std::nan("")), std::invalid_argument);
}

TEST(LengthPolynomial, PartialDerivativesMatchFiniteDifferences) {
  const int d = 3, o = 4;
  const fm::LengthPolynomial p(d, o, random_coefficients(d, o, 5));
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int s = 0; s < 10; ++s) {
    std::vector<double> x(d);
    for (double& v : x) v = u(rng);
    for (int k = 0; k < d; ++k) {
      const fm::LengthPolynomial dk = p.derivative(k);
      EXPECT_EQ(dk.order(), o - 1);
      auto along = [&](double xk) {
        std::vector<double> y = x;
        y[k] = xk;
        return p.value(y.data());
      };
      EXPECT_MATCHES_FINITE_DIFFERENCE(dk.value(x.data()), central_difference(along, x[k], default_step(x[k], 1.0)));
    }
  }
  EXPECT_EQ(fm::LengthPolynomial(2, 0, {4.0}).derivative(1).value(std::vector<double>{1.0, 2.0}.data()), 0.0);
}

TEST(LengthPolynomial, TimeDerivativesAlongACurveMatchFiniteDifferencesInTime) {
  const int d = 3, o = 4;
  const fm::LengthPolynomial p(d, o, random_coefficients(d, o, 6));
  const JointMotion motion = random_motion(d, 8);
  const int count = fm::LengthPolynomial::kMaxJetCount;
  for (double t : {-0.4, 0.1, 0.6}) {
    double jet[count];
    p.timeDerivatives(motion.jet(t, count).data(), count, jet);
    EXPECT_NEAR(jet[0], p.value(motion.jet(t, 1).data()), 1e-15);
    for (int j = 0; j + 1 < count; ++j) {
      auto order_j = [&](double s) {
        double out[count];
        p.timeDerivatives(motion.jet(s, count).data(), count, out);
        return out[j];
      };
      EXPECT_MATCHES_FINITE_DIFFERENCE(jet[j + 1], central_difference(order_j, t, default_step(t, 1.0))) << "order " << j + 1;
    }
  }
}

// The first two time derivatives by the chain rule through the partial-derivative polynomials,
// an independent route: dP = sum_k P_k x_k', ddP = sum_kl P_kl x_k' x_l' + sum_k P_k x_k''.
// Orders up to 40: the arguments' powers come from a table up to 64 rows and from repeated
// products beyond it (two arguments to order 40 need 82 rows), the same numbers either way.
TEST(LengthPolynomial, TimeDerivativesFollowTheChainRuleAtLowAndHighOrders) {
  for (const auto& [d, o] : {std::pair{3, 4}, std::pair{1, 12}, std::pair{3, 20}, std::pair{2, 40}}) {
    const fm::LengthPolynomial p(d, o, random_coefficients(d, o, 17));
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-0.9, 0.9);
    std::vector<double> jet_in(static_cast<std::size_t>(3 * d));
    for (double& v : jet_in) v = u(rng);
    const double* x = jet_in.data();
    const double *xd = x + d, *xdd = x + 2 * d;
    double jet[3];
    p.timeDerivatives(x, 3, jet);
    double first = 0.0, second = 0.0;
    for (int k = 0; k < d; ++k) {
      const fm::LengthPolynomial pk = p.derivative(k);
      first += pk.value(x) * xd[k];
      second += pk.value(x) * xdd[k];
      for (int l = 0; l < d; ++l) second += pk.derivative(l).value(x) * xd[k] * xd[l];
    }
    EXPECT_NEAR(jet[0], p.value(x), 1e-12 * (1.0 + std::abs(jet[0]))) << "d " << d << " o " << o;
    EXPECT_NEAR(jet[1], first, 1e-11 * (1.0 + std::abs(first))) << "d " << d << " o " << o;
    EXPECT_NEAR(jet[2], second, 1e-10 * (1.0 + std::abs(second))) << "d " << d << " o " << o;
  }
}

TEST(LengthPolynomial, BadInputIsNamed) {
  try {
    fm::LengthPolynomial(2, 3, std::vector<double>(9, 0.0));
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("need 10 coefficients, got 9"), std::string::npos) << e.what();
  }
  EXPECT_THROW(fm::LengthPolynomial(1, 1, {0.0, std::nan("")}), std::invalid_argument);
  EXPECT_THROW(fm::LengthPolynomial(-1, 1, {0.0}), std::invalid_argument);
  EXPECT_THROW(fm::LengthPolynomial(fm::LengthPolynomial::kMaxDimension + 1, 0, {0.0}), std::invalid_argument);
  EXPECT_THROW(fm::LengthPolynomial(1, -1, {}), std::invalid_argument);
  EXPECT_THROW(fm::LengthPolynomial(2, 1, {1, 2, 3}).derivative(2), std::invalid_argument);
  double out[6];
  const double x[6] = {};
  EXPECT_THROW(fm::LengthPolynomial(1, 1, {1, 2}).timeDerivatives(x, 6, out), std::invalid_argument);
}

TEST(MusculotendonPath, ConstantMomentArmsAreTheOrderOneCase) {
  const std::vector<double> d{0.03, 0.0, -0.02};
  const auto path = fm::MusculotendonPath::constantMomentArms(0.4, d);
  EXPECT_TRUE(path.hasConstantMomentArms());
  EXPECT_EQ(path.crossedJoints(), (std::vector<int>{0, 2}));
  const JointMotion motion = random_motion(3, 9);
  const auto q = motion.jet(0.3, 3);
  EXPECT_NEAR(path.length(q.data()), 0.4 - 0.03 * q[0] + 0.02 * q[2], 1e-16);
  double r[3], jac[9], L[3], rj[9];
  path.momentArms(q.data(), r);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(r[i], d[i]);
  path.momentArmJacobian(q.data(), jac);
  for (double v : jac) EXPECT_EQ(v, 0.0);
  path.lengthJet(q.data(), 3, L);
  EXPECT_NEAR(L[1], -(0.03 * q[3] - 0.02 * q[5]), 1e-16);
  EXPECT_NEAR(L[2], -(0.03 * q[6] - 0.02 * q[8]), 1e-16);
  path.momentArmJets(q.data(), 3, rj);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(rj[i], d[i]);
    EXPECT_EQ(rj[3 + i], 0.0);
    EXPECT_EQ(rj[6 + i], 0.0);
  }
}

// Arguments (joint 2, held 0.5 rad, joint 0) of a cubic; joint 1 is not part of the path.
fm::MusculotendonPath held_path() {
  return fm::MusculotendonPath(fm::LengthPolynomial(3, 3, random_coefficients(3, 3, 11)),
                               {{2, 0.0}, {-1, 0.5}, {0, 0.0}}, 3);
}

TEST(MusculotendonPath, HeldCoordinatesEnterAtTheirValue) {
  const auto path = held_path();
  EXPECT_FALSE(path.hasConstantMomentArms());
  EXPECT_EQ(path.crossedJoints(), (std::vector<int>{0, 2}));
  const double q[3] = {0.2, -0.7, 1.1};
  const double x[3] = {1.1, 0.5, 0.2};
  // Evaluated with the held value substituted into the coefficients: equal up to rounding.
  EXPECT_NEAR(path.length(q), path.lengthPolynomial().value(x), 1e-15);
}

TEST(MusculotendonPath, MomentArmsAreTheNegativeGradientAndTheirJetsMatchFiniteDifferences) {
  const auto path = held_path();
  const int n = 3;
  const JointMotion motion = random_motion(n, 12);
  for (double t : {-0.3, 0.2, 0.5}) {
    const auto q = motion.jet(t, 1);
    double r[n], jac[n * n];
    path.momentArms(q.data(), r);
    path.momentArmJacobian(q.data(), jac);
    EXPECT_EQ(r[1], 0.0);
    for (int i = 0; i < n; ++i) {
      auto length_along = [&](double qi) {
        std::vector<double> y = q;
        y[i] = qi;
        return path.length(y.data());
      };
      EXPECT_MATCHES_FINITE_DIFFERENCE(-r[i], central_difference(length_along, q[i], default_step(q[i], 1.0)));
      for (int k = 0; k < n; ++k) {
        auto arm_along = [&](double qk) {
          std::vector<double> y = q;
          y[k] = qk;
          double rr[n];
          path.momentArms(y.data(), rr);
          return rr[i];
        };
        EXPECT_MATCHES_FINITE_DIFFERENCE(jac[i * n + k], central_difference(arm_along, q[k], default_step(q[k], 1.0)));
      }
    }
    // Jets in time: each order against the finite difference of the one below.
    const int count = 4;
    const auto qj = motion.jet(t, count);
    double L[count], rj[count * n];
    path.lengthJet(qj.data(), count, L);
    path.momentArmJets(qj.data(), count, rj);
    double power = 0.0;  // dL/dt = -r^T qd
    for (int i = 0; i < n; ++i) power -= r[i] * qj[n + i];
    EXPECT_NEAR(L[1], power, 1e-14);
    for (int j = 0; j + 1 < count; ++j) {
      auto length_j = [&](double s) {
        double out[count];
        path.lengthJet(motion.jet(s, count).data(), count, out);
        return out[j];
      };
      EXPECT_MATCHES_FINITE_DIFFERENCE(L[j + 1], central_difference(length_j, t, default_step(t, 1.0)));
      for (int i = 0; i < n; ++i) {
        auto arm_j = [&](double s) {
          double out[count * n];
          path.momentArmJets(motion.jet(s, count).data(), count, out);
          return out[j * n + i];
        };
        EXPECT_MATCHES_FINITE_DIFFERENCE(rj[(j + 1) * n + i], central_difference(arm_j, t, default_step(t, 1.0)));
      }
    }
  }
}

TEST(MusculotendonPath, BadCoordinatesAreNamed) {
  const fm::LengthPolynomial p(2, 1, {0.3, 0.01, 0.02});
  EXPECT_THROW(fm::MusculotendonPath(p, {{0, 0.0}}, 2), std::invalid_argument);
  EXPECT_THROW(fm::MusculotendonPath(p, {{0, 0.0}, {2, 0.0}}, 2), std::invalid_argument);
  try {
    fm::MusculotendonPath(p, {{1, 0.0}, {1, 0.0}}, 2);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("joint 1 is given twice"), std::string::npos) << e.what();
  }
  EXPECT_THROW(fm::MusculotendonPath(p, {{-1, std::nan("")}, {0, 0.0}}, 2), std::invalid_argument);
}
