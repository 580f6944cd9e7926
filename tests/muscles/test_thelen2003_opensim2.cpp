// OpenSim 2.x's Thelen muscle against its equations written out here once more (OpenSim 2.x's
// Thelen2003Muscle::calcTendonForce, calcPassiveForce, calcFiberVelocity as they read in 2011),
// its inverses by round trip, its velocity law's partials against differences, and the shared
// balance handing the velocity to the model's own law.

#include <cmath>

#include <gtest/gtest.h>

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/muscles/muscle_model.hpp"
#include "flatsos/muscles/thelen2003_opensim2_muscle.hpp"

namespace {

using namespace flatsos::muscles;

MuscleParameters opensim2_muscle() {
  MuscleParameters p;
  p.name = "BIClong";
  p.model = muscle_model_named("thelen2003_opensim2");
  p.model->setDefaults(p);
  p.max_isometric_force_N = 624.3;
  p.optimal_fiber_length_m = 0.1157;
  p.tendon_slack_length_m = 0.2723;
  p.pennation_angle_at_optimal_rad = 0.0;
  validate(p);
  return p;
}

// The normalized laws as OpenSim 2.x wrote them (e0 = 0.033, kPE = 4, e0M = 0.6, Af = 0.3,
// Flen = 1.8, damping 0.05).
double tendon_2x(double eps) {
  const double e0 = 0.033, eps_toe = 0.609 * e0, f_toe = 0.333333, klin = 1.712 / e0;
  double f = 0.0;
  if (eps > eps_toe) f = klin * (eps - eps_toe) + f_toe;
  else if (eps > 0.0) f = f_toe / (std::exp(3.0) - 1.0) * (std::exp(3.0 * eps / eps_toe) - 1.0);
  return f + 0.001 * (1.0 + eps);
}
double passive_2x(double l) {
  if (l > 1.6) return 1.0 + 4.0 / 0.6 * (l - 1.6);
  return std::exp(4.0 * (l - 1.0) / 0.6) / std::exp(4.0);
}
double lengthening_2x(double fv, double fa) {
  const double af = 0.3, flen = 1.8, d = 0.05;
  auto c = [&](double f) { return (f - fa) / (fa + f / af + d); };
  auto e = [&](double f) { return (f - fa) / ((2.0 + 2.0 / af) * (fa * flen - f) / (flen - 1.0) + d); };
  if (fv < 0.0) return c(0.0) + fv * (c(1e-6) - c(0.0)) / 1e-6;
  if (fv < fa) return c(fv);
  if (fv < 0.95 * fa * flen) return e(fv);
  const double f0 = 0.95 * fa * flen, f1 = (0.95 + 1e-6) * fa * flen;
  return e(f0) + (e(f1) - e(f0)) / (f1 - f0) * (fv - f0);
}

TEST(Thelen2003OpenSim2, TendonAndPassiveCurvesAreOpenSim2sAtAThousandPoints) {
  const MuscleParameters p = opensim2_muscle();
  for (int i = 0; i < 1000; ++i) {
    const double eps = -0.01 + 0.06 * i / 999.0;
    const double tendon_N = p.model->tendonForce(p, p.tendon_slack_length_m * (1.0 + eps)).value;
    EXPECT_NEAR(tendon_N / p.max_isometric_force_N, tendon_2x(eps), 1e-9 * tendon_2x(eps)) << eps;
    if (tendon_N > 0.0) {
      EXPECT_NEAR(p.model->tendonLengthFromForce(p, tendon_N), p.tendon_slack_length_m * (1.0 + eps), 1e-12) << eps;
    }
    const double l = 0.4 + 1.4 * i / 999.0;
    EXPECT_NEAR(p.model->passiveFiberForce(p, l * p.optimal_fiber_length_m).value / p.max_isometric_force_N, passive_2x(l),
                1e-9 * passive_2x(l)) << l;
  }
}

TEST(Thelen2003OpenSim2, TheVelocityLawIsOpenSim2sAndItsPartialsAreExact) {
  const MuscleParameters p = opensim2_muscle();
  for (int i = 0; i < 1000; ++i) {
    const double a = (i % 10) / 9.0 * 0.999, l = 0.6 + 0.8 * ((i / 10) % 10) / 9.0;
    const double fv = -0.2 + 2.2 * (i / 100) / 9.0;
    const double length_m = l * p.optimal_fiber_length_m;
    const double fa = std::max(a, 1e-6) * std::exp(-(l - 1.0) * (l - 1.0) / 0.5);
    const double vmax_m_per_s = (5.0 + a * 5.0) * p.optimal_fiber_length_m;
    const OwnFiberVelocity v = p.model->ownFiberVelocity(p, a, length_m, fv * p.max_isometric_force_N);
    const double expected = -vmax_m_per_s * lengthening_2x(fv, fa);
    EXPECT_NEAR(v.shortening_m_per_s, expected, 1e-9 * (1.0 + std::abs(expected))) << a << " " << l << " " << fv;
    const double h = 1e-4 * p.max_isometric_force_N;
    const auto at = [&](double force_N) { return p.model->ownFiberVelocity(p, a, length_m, force_N).shortening_m_per_s; };
    const double fv_N = fv * p.max_isometric_force_N;
    EXPECT_NEAR(v.d_fiber_force, (at(fv_N + h) - at(fv_N - h)) / (2 * h), 1e-4 * (1.0 + std::abs(v.d_fiber_force)));
    // The partials in the fibre's length and the activation (the muscle's inverse solves the law
    // for a and differentiates it), away from the law's kinks (Fv = 0, Fa, 0.95 Fa Flen) and the
    // activation floor.
    if (a < 0.01 || std::abs(fv) < 1e-3 || std::abs(fv - fa) < 1e-3 || std::abs(fv - 0.95 * 1.8 * fa) < 1e-3) continue;
    // Fourth-order differences with steps of 1e-4: the extrapolation below Fv = 0 is a
    // difference quotient over 1e-6 itself, so smaller steps meet its rounding.
    const auto five_point = [](auto&& g, double x, double step) {
      return (-g(x + 2 * step) + 8 * g(x + step) - 8 * g(x - step) + g(x - 2 * step)) / (12 * step);
    };
    const double d_length = five_point([&](double x) { return p.model->ownFiberVelocity(p, a, x, fv_N).shortening_m_per_s; },
                                       length_m, 1e-4 * p.optimal_fiber_length_m);
    const double d_activation = five_point(
        [&](double x) { return p.model->ownFiberVelocity(p, x, length_m, fv_N).shortening_m_per_s; }, a, 1e-4);
    EXPECT_NEAR(v.d_fiber_length, d_length, 1e-5 * (1.0 + std::abs(d_length))) << a << " " << l << " " << fv;
    EXPECT_NEAR(v.d_activation, d_activation, 1e-5 * (1.0 + std::abs(d_activation))) << a << " " << l << " " << fv;
  }
}

TEST(Thelen2003OpenSim2, TheForwardModelUsesTheOwnLawAndTheActivationHasConstantTimeConstants) {
  const MuscleParameters p = opensim2_muscle();
  const double tendon_m = p.tendon_slack_length_m * 1.01, along_m = 0.11, a = 0.3;
  const double force_N = p.model->tendonForce(p, tendon_m).value;
  const double fiber_force_N = force_N - p.model->passiveFiberForce(p, along_m).value;  // no pennation
  EXPECT_DOUBLE_EQ(fiber_shortening_velocity(p, force_N, a, along_m),
                   p.model->ownFiberVelocity(p, a, along_m, fiber_force_N).shortening_m_per_s);
  // da/dt = (n - a) / T, T = 0.01 s up and 0.04 s down, whatever a is; the inverse gives n back.
  for (const double n : {0.0, 0.2, 0.9}) {
    const double rate = p.model->activationRate(p, n, a).value;
    EXPECT_DOUBLE_EQ(rate, (n - a) / (n >= a ? 0.01 : 0.04));
    EXPECT_NEAR(p.model->excitationFromActivation(p, a, rate).excitation, n, 1e-15);
  }
  EXPECT_DOUBLE_EQ(p.model->activationRate(p, 0.01, 0.0).value, 1.0);  // no minimum activation
}

}  // namespace
