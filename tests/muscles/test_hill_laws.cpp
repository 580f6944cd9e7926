// Property tests for the Hill muscle laws (docs/method/flatness.md): values at known points,
// monotonicity, limits, inverse round trips, finite-difference twins of every derivative,
// and the safe extension of the forward model.
#include <gtest/gtest.h>

#include "finite_difference.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/muscles/static_equilibrium.hpp"

namespace fm = flatsos::muscles;

namespace {

fm::MuscleParameters biceps() {
  fm::MuscleParameters p;
  p.name = "biceps";
  p.max_isometric_force_N = 1000.0;
  p.optimal_fiber_length_m = 0.1422;
  p.tendon_slack_length_m = 0.2298;
  return p;
}

// The same muscle with pennation (0.4 rad) and passive fibre force (e0 = 0.5).
std::vector<fm::MuscleParameters> variants() {
  fm::MuscleParameters pennated = biceps();
  pennated.name = "biceps, pennated with passive force";
  pennated.pennation_angle_at_optimal_rad = 0.4;
  pennated.passive_fiber_strain_at_one_norm_force = 0.5;
  // Damping makes the force balance implicit in the velocity; Thelen's maximum velocity scales
  // with activation.
  fm::MuscleParameters damped = pennated;
  damped.name = "biceps, pennated, passive and damped";
  damped.fiber_damping = 0.1;
  fm::MuscleParameters thelen = biceps();
  thelen.name = "biceps, Thelen 2003, damped";
  thelen.model = fm::muscle_model_named("thelen2003");
  thelen.model->setDefaults(thelen);
  thelen.fiber_damping = 0.05;
  return {biceps(), pennated, damped, thelen};
}

using flatsos::test::central_difference;
using flatsos::test::default_step;

std::vector<double> linspace(double a, double b, int n) {
  std::vector<double> v;
  for (int i = 0; i < n; ++i) v.push_back(a + (b - a) * i / (n - 1));
  return v;
}

}  // namespace

TEST(Tendon, ForceIsFmaxAtFourPercentStrainAndZeroWhenSlack) {
  const auto p = biceps();
  EXPECT_NEAR(fm::tendon_force(p, 1.04 * p.tendon_slack_length_m), 1000.0, 1e-9);
  EXPECT_EQ(fm::tendon_force(p, p.tendon_slack_length_m), 0.0);
  EXPECT_EQ(fm::tendon_force(p, 0.5 * p.tendon_slack_length_m), 0.0);
  EXPECT_EQ(fm::tendon_force_derivative(p, 0.9 * p.tendon_slack_length_m), 0.0);
}

TEST(Tendon, InverseRoundTrip) {
  const auto p = biceps();
  for (double f : {1e-6, 0.1, 1.0, 10.2, 108.0, 999.0, 1500.0}) {
    const double ls = fm::tendon_length_from_force(p, f);
    EXPECT_NEAR(fm::tendon_force(p, ls), f, 1e-12 * std::max(1.0, f)) << f;
  }
  for (double ls : linspace(p.tendon_slack_length_m * 1.0001, p.tendon_slack_length_m * 1.06, 50))
    EXPECT_NEAR(fm::tendon_length_from_force(p, fm::tendon_force(p, ls)), ls, 1e-14);
}

TEST(Tendon, InverseRejectsNonPositiveAndNaNForce) {
  const auto p = biceps();
  EXPECT_THROW(fm::tendon_length_from_force(p, 0.0), std::domain_error);
  EXPECT_THROW(fm::tendon_length_from_force(p, -1.0), std::domain_error);
  EXPECT_THROW(fm::tendon_length_from_force(p, std::nan("")), std::domain_error);
  try {
    fm::tendon_length_from_force(p, -1.0);
  } catch (const std::domain_error& e) {
    EXPECT_NE(std::string(e.what()).find("biceps"), std::string::npos);
  }
}

TEST(Tendon, DerivativesMatchFiniteDifferences) {
  const auto p = biceps();
  // Steps well inside the distance to the slack length (the kink of the tendon law).
  const double h = 1e-7;
  for (double ls : linspace(1.001 * p.tendon_slack_length_m, 1.05 * p.tendon_slack_length_m, 20)) {
    EXPECT_MATCHES_FINITE_DIFFERENCE(fm::tendon_force_derivative(p, ls),
                                     central_difference([&](double x) { return fm::tendon_force(p, x); }, ls, h));
    EXPECT_MATCHES_FINITE_DIFFERENCE(
        fm::tendon_force_second_derivative(p, ls),
        central_difference([&](double x) { return fm::tendon_force_derivative(p, x); }, ls, h));
  }
}

TEST(ForceLength, PeakAtOptimalLengthAndDerivative) {
  const auto p = biceps();
  EXPECT_DOUBLE_EQ(fm::force_length(p, p.optimal_fiber_length_m), 1.0);
  EXPECT_NEAR(fm::force_length(p, p.optimal_fiber_length_m * (1.0 + p.force_length_width)),
              std::exp(-1.0), 1e-15);
  for (double lc : linspace(0.3 * p.optimal_fiber_length_m, 1.8 * p.optimal_fiber_length_m, 40)) {
    const double f = fm::force_length(p, lc);
    EXPECT_GT(f, 0.0);
    EXPECT_LE(f, 1.0);
    EXPECT_MATCHES_FINITE_DIFFERENCE(
        fm::force_length_derivative(p, lc),
        central_difference([&](double x) { return fm::force_length(p, x); }, lc, default_step(lc, p.optimal_fiber_length_m)));
  }
}

TEST(ForceVelocity, KnownValuesAndLimits) {
  const auto p = biceps();
  const double vmax = p.max_shortening_velocity_m_per_s();
  EXPECT_DOUBLE_EQ(fm::force_velocity(p, 0.0), 1.0);
  EXPECT_NEAR(fm::force_velocity(p, vmax), 0.0, 1e-15);
  EXPECT_NEAR(fm::force_velocity(p, -1e9 * vmax), p.max_eccentric_force_ratio, 1e-8);
  EXPECT_LT(fm::force_velocity(p, -1e3 * vmax), p.max_eccentric_force_ratio);
}

TEST(ForceVelocity, StrictlyDecreasingAndDerivativeMatchesFiniteDifferences) {
  const auto p = biceps();
  const double vmax = p.max_shortening_velocity_m_per_s();
  const auto us = linspace(-5.0 * vmax, vmax, 601);
  for (std::size_t i = 1; i < us.size(); ++i)
    EXPECT_LT(fm::force_velocity(p, us[i]), fm::force_velocity(p, us[i - 1])) << us[i];
  for (double u : us) {
    const double h = default_step(0.0, 1e-3 * vmax);
    if (std::abs(u) < 3 * h) continue;  // the two branches meet (C1) at u = 0
    EXPECT_MATCHES_FINITE_DIFFERENCE(fm::force_velocity_derivative(p, u),
                                     central_difference([&](double x) { return fm::force_velocity(p, x); }, u, h))
        << u;
    EXPECT_LT(fm::force_velocity_derivative(p, u), 0.0);
  }
  // C1 at u = 0: both branches have the same slope there.
  EXPECT_NEAR(fm::force_velocity_derivative(p, -1e-300), fm::force_velocity_derivative(p, 0.0),
              1e-12);
}

TEST(ForceVelocity, InverseRoundTripsOverTheValidDomain) {
  const auto p = biceps();
  const double vmax = p.max_shortening_velocity_m_per_s();
  for (double u : linspace(-20.0 * vmax, vmax, 2001)) {
    const double z = fm::force_velocity(p, u);
    EXPECT_NEAR(fm::force_velocity_inverse(p, z), u, 1e-12 * std::max(1.0, std::abs(u))) << u;
  }
  for (double z : linspace(1e-9, p.max_eccentric_force_ratio - 1e-6, 2001)) {
    const double u = fm::force_velocity_inverse(p, z);
    EXPECT_NEAR(fm::force_velocity(p, u), z, 1e-12) << z;
  }
  EXPECT_THROW(fm::force_velocity_inverse(p, p.max_eccentric_force_ratio), std::domain_error);
  EXPECT_THROW(fm::force_velocity_inverse(p, std::nan("")), std::domain_error);
}

TEST(ForceVelocity, SafeExtensionIsExactInsideC1AtTheSeamsAndMonotone) {
  const auto p = biceps();
  const double z_hi = fm::force_ratio_exact_upper_bound(p);
  EXPECT_GT(z_hi, 1.0);
  EXPECT_LT(z_hi, p.max_eccentric_force_ratio);
  for (double z : linspace(0.0, z_hi, 200))
    EXPECT_DOUBLE_EQ(fm::fiber_velocity_from_force_ratio(p, z), fm::force_velocity_inverse(p, z));
  for (double seam : {0.0, z_hi}) {
    const double eps = 1e-9;
    EXPECT_NEAR(fm::fiber_velocity_from_force_ratio(p, seam - eps),
                fm::fiber_velocity_from_force_ratio(p, seam + eps), 1e-6);
    EXPECT_NEAR(fm::fiber_velocity_from_force_ratio_derivative(p, seam - eps),
                fm::fiber_velocity_from_force_ratio_derivative(p, seam + eps),
                1e-6 * std::abs(fm::fiber_velocity_from_force_ratio_derivative(p, seam)));
  }
  const auto zs = linspace(-10.0, 1e4, 20001);
  for (std::size_t i = 1; i < zs.size(); ++i) {
    const double u = fm::fiber_velocity_from_force_ratio(p, zs[i]);
    EXPECT_TRUE(std::isfinite(u));
    EXPECT_LT(u, fm::fiber_velocity_from_force_ratio(p, zs[i - 1]));
  }
  for (double z : linspace(-3.0, 5.0, 161)) {
    const double h = default_step(0.0, 1e-3);
    // The branches meet at 0, z_hi and 1: keep the samples 3 steps away.
    if (std::abs(z) < 3 * h || std::abs(z - z_hi) < 3 * h || std::abs(z - 1.0) < 3 * h) continue;
    EXPECT_MATCHES_FINITE_DIFFERENCE(
        fm::fiber_velocity_from_force_ratio_derivative(p, z),
        central_difference([&](double x) { return fm::fiber_velocity_from_force_ratio(p, x); }, z, h))
        << z;
  }
}

TEST(ContractionDynamics, IsometricAtForceEqualToActiveCapacity) {
  const auto p = biceps();
  const double lc = 0.13, a = 0.4;
  const double f_iso = a * p.max_isometric_force_N * fm::force_length(p, lc);
  EXPECT_NEAR(fm::fiber_shortening_velocity(p, f_iso, a, lc), 0.0, 1e-14);
  EXPECT_GT(fm::fiber_shortening_velocity(p, 0.5 * f_iso, a, lc), 0.0);  // concentric
  EXPECT_LT(fm::fiber_shortening_velocity(p, 1.2 * f_iso, a, lc), 0.0);  // eccentric
}

TEST(ContractionDynamics, NeverNaNOrInfOverAWideSweep) {
  for (const auto& p : variants()) {
    SCOPED_TRACE(p.name);
    const double ls_slack = p.tendon_slack_length_m;
    for (double a : {0.0, 1e-12, 1e-6, p.activation_floor, 0.01, 0.5, 1.0})
      for (double ls : linspace(0.5 * ls_slack, 1.2 * ls_slack, 71))
        for (double L : linspace(0.0, 1.0, 41))
          for (double dL : {-10.0, 0.0, 10.0}) {
            const double d = fm::tendon_length_derivative(p, ls, a, L, dL);
            ASSERT_TRUE(std::isfinite(d)) << a << " " << ls << " " << L << " " << dL;
          }
  }
}

TEST(ContractionDynamics, TendonOdePartialsMatchFiniteDifferences) {
  // Over the forward model's whole range (the grid avoids the slack length itself, where the
  // tendon force has a second-derivative kink): concentric, eccentric, the extension beyond
  // z_hi, slack tendons, activations below and above the floor.
  for (const auto& p : variants()) {
    SCOPED_TRACE(p.name);
    int checked = 0;
    for (double a : {0.0, 5e-5, 2e-4, 1e-3, 0.05, 0.4, 1.0})
      for (double ls : linspace(p.tendon_slack_length_m - 0.0015, p.tendon_slack_length_m + 0.0125, 15))
        for (double L : linspace(0.3, 0.45, 7)) {
          const auto d = fm::tendon_length_derivative_partials(p, ls, a, L);
          auto ode = [&](double x, double y) { return fm::tendon_length_derivative(p, x, y, L, 0.0); };
          // Lengths on the scale of the tendon's stretch at Fmax (0.04 L_slack, ~9 mm), which the
          // samples keep away from slack; activations on their own scale (down to 1e-4: below it the
          // ODE curves on the scale of a itself).
          const double hl = default_step(0.0, 1e-3 * p.tendon_slack_length_m), ha = default_step(0.0, 1e-2 * std::max(a, 1e-4));
          if (std::abs(ls - p.tendon_slack_length_m) > 3 * hl) {  // slack is a kink
            EXPECT_MATCHES_FINITE_DIFFERENCE(d.d_tendon_length_per_s, central_difference([&](double x) { return ode(x, a); }, ls, hl))
                << a << " " << ls << " " << L;
            EXPECT_MATCHES_FINITE_DIFFERENCE(
                d.d_musculotendon_length_per_s,
                central_difference([&](double x) { return fm::tendon_length_derivative(p, ls, a, x, 0.0); }, L, hl))
                << a << " " << ls << " " << L;
          }
          if (std::abs(a - p.activation_floor) > 3.0 * ha) {  // the floor is a kink
            EXPECT_MATCHES_FINITE_DIFFERENCE(d.d_activation_m_per_s, central_difference([&](double y) { return ode(ls, y); }, a, ha))
                << a << " " << ls << " " << L;
          }
          ++checked;
        }
    EXPECT_EQ(checked, 7 * 15 * 7);
    // The stiff direction: lengthening the tendon at a tiny activation must slow it strongly.
    const auto low = fm::tendon_length_derivative_partials(p, p.tendon_slack_length_m + 0.005, 1e-3, 0.37);
    EXPECT_LT(low.d_tendon_length_per_s, -1e3);
  }
}

TEST(ContractionDynamics, ActivationFloorBoundsTheForceRatio) {
  const auto p = biceps();
  const double lc = p.optimal_fiber_length_m;
  EXPECT_DOUBLE_EQ(fm::force_ratio(p, 100.0, 0.0, lc), fm::force_ratio(p, 100.0, p.activation_floor, lc));
  EXPECT_DOUBLE_EQ(fm::force_ratio(p, 100.0, 0.5, lc), 100.0 / (0.5 * 1000.0));
  EXPECT_TRUE(std::isfinite(fm::force_ratio(p, 100.0, 0.0, 1e3)));  // f underflows there
}

TEST(ActivationDynamics, FasterActivationThanDeactivation) {
  const auto p = biceps();
  EXPECT_NEAR(fm::activation_derivative(p, 1.0, 0.0), 1.0 / p.activation_time_constant_s, 1e-12);
  EXPECT_NEAR(-fm::activation_derivative(p, 0.0, 1.0), 1.0 / p.deactivation_time_constant_s, 1e-12);
  EXPECT_GT(fm::activation_derivative(p, 1.0, 0.5), -fm::activation_derivative(p, 0.0, 0.5));
  EXPECT_EQ(fm::activation_derivative(p, 0.3, 0.3), 0.0);
}

TEST(ActivationDynamics, PartialDerivativesMatchFiniteDifferences) {
  const auto p = biceps();
  for (double n : linspace(0.0, 1.0, 11))
    for (double a : linspace(0.0, 1.0, 11)) {
      const double h = default_step(0.0, 1.0);
      EXPECT_MATCHES_FINITE_DIFFERENCE(fm::activation_derivative_d_excitation(p, n, a),
                                       central_difference([&](double x) { return fm::activation_derivative(p, x, a); }, n, h));
      EXPECT_MATCHES_FINITE_DIFFERENCE(fm::activation_derivative_d_activation(p, n, a),
                                       central_difference([&](double x) { return fm::activation_derivative(p, n, x); }, a, h));
    }
}

TEST(ActivationDynamics, InverseRoundTrips) {
  const auto p = biceps();
  for (double n : linspace(0.0, 1.0, 101))
    for (double a : linspace(0.0, 1.0, 101)) {
      const double adot = fm::activation_derivative(p, n, a);
      const auto inv = fm::excitation_from_activation(p, a, adot);
      ASSERT_TRUE(inv.real_root);
      // The two roots sum to a - beta / (1 - beta). For a > beta / (1 - beta) both can lie in
      // [0, 1] and give the same da/dt (sigma(n) (n - a) is not monotone in n there); the
      // inverse returns the larger one, which is continuous along trajectories.
      const double other_root = a - p.activation_beta() / (1.0 - p.activation_beta()) - n;
      EXPECT_NEAR(inv.excitation, std::max(n, other_root), 1e-12) << "n=" << n << " a=" << a;
      EXPECT_NEAR(fm::activation_derivative(p, inv.excitation, a), adot, 1e-12 * 100.0);
    }
  // Equilibrium: da/dt = 0 gives n = a.
  EXPECT_NEAR(fm::excitation_from_activation(p, 0.37, 0.0).excitation, 0.37, 1e-15);
}

TEST(ActivationDynamics, UnattainableRateIsFlagged) {
  const auto p = biceps();
  // Deactivating faster than the decay with n at the vertex of the quadratic is impossible.
  const auto inv = fm::excitation_from_activation(p, 0.5, -1e4);
  EXPECT_FALSE(inv.real_root);
  EXPECT_FALSE(inv.in_unit_interval());
  // An activation rate above what n = 1 gives needs n > 1: a real root outside [0, 1].
  const auto high = fm::excitation_from_activation(p, 0.2, 2.0 * fm::activation_derivative(p, 1.0, 0.2));
  EXPECT_TRUE(high.real_root);
  EXPECT_GT(high.excitation, 1.0);
  EXPECT_FALSE(high.in_unit_interval());
}

TEST(PassiveFiberForce, ZeroUpToOptimalFmaxAtItsStrainC2AndIncreasing) {
  auto p = biceps();
  const double lopt = p.optimal_fiber_length_m;
  for (double l : linspace(0.2 * lopt, 2.0 * lopt, 50)) EXPECT_EQ(fm::passive_fiber_force(p, l), 0.0);  // off
  p.passive_fiber_strain_at_one_norm_force = 0.6;
  EXPECT_NEAR(fm::passive_fiber_force(p, 1.6 * lopt), p.max_isometric_force_N, 1e-9 * p.max_isometric_force_N);
  EXPECT_EQ(fm::passive_fiber_force(p, lopt), 0.0);
  EXPECT_EQ(fm::passive_fiber_force(p, 0.7 * lopt), 0.0);
  // C2 at the optimal length: value, slope and curvature go to 0 from above.
  const double just_above = lopt * (1.0 + 1e-6);
  EXPECT_LT(fm::passive_fiber_force(p, just_above), 1e-12);
  EXPECT_LT(fm::passive_fiber_force_derivative(p, just_above), 1e-6);
  EXPECT_LT(fm::passive_fiber_force_second_derivative(p, just_above), 1.0);
  double previous = 0.0;
  for (double l : linspace(lopt * 1.001, 2.0 * lopt, 60)) {
    const double force = fm::passive_fiber_force(p, l);
    EXPECT_GT(force, previous);
    previous = force;
    const double h = default_step(l, lopt);
    EXPECT_MATCHES_FINITE_DIFFERENCE(fm::passive_fiber_force_derivative(p, l),
                                     central_difference([&](double x) { return fm::passive_fiber_force(p, x); }, l, h));
    EXPECT_MATCHES_FINITE_DIFFERENCE(
        fm::passive_fiber_force_second_derivative(p, l),
        central_difference([&](double x) { return fm::passive_fiber_force_derivative(p, x); }, l, h));
  }
  // Across the series/exp switch of the implementation (y = 0.1) the curve is smooth.
  const double switch_length = lopt * (1.0 + 0.1 * 0.6 / 4.0);
  EXPECT_NEAR(fm::passive_fiber_force(p, switch_length * (1 - 1e-12)), fm::passive_fiber_force(p, switch_length * (1 + 1e-12)),
              1e-9 * fm::passive_fiber_force(p, switch_length));
}

TEST(Pennation, ConstantThicknessGeometryAndItsDerivatives) {
  auto p = biceps();
  const auto straight = fm::fiber_geometry(p, 0.123);
  EXPECT_EQ(straight.length_m, 0.123);
  EXPECT_EQ(straight.cos_pennation, 1.0);
  p.pennation_angle_at_optimal_rad = 0.4;
  const double lopt = p.optimal_fiber_length_m;
  // At the optimal fibre length the angle is phi0.
  const auto at_opt = fm::fiber_geometry(p, lopt * std::cos(0.4));
  EXPECT_NEAR(at_opt.length_m, lopt, 1e-15);
  EXPECT_NEAR(at_opt.cos_pennation, std::cos(0.4), 1e-15);
  for (double x : linspace(0.2 * lopt, 1.8 * lopt, 30)) {
    const auto g = fm::fiber_geometry(p, x);
    EXPECT_NEAR(g.length_m * std::sqrt(1.0 - g.cos_pennation * g.cos_pennation), p.fiber_thickness_m(), 1e-15);
    const double h = default_step(x, lopt);
    EXPECT_MATCHES_FINITE_DIFFERENCE(g.length_d_along,
                                     central_difference([&](double y) { return fm::fiber_geometry(p, y).length_m; }, x, h));
    EXPECT_MATCHES_FINITE_DIFFERENCE(
        g.cos_pennation_d_along, central_difference([&](double y) { return fm::fiber_geometry(p, y).cos_pennation; }, x, h));
  }
}

TEST(ContractionDynamics, PennatedPassiveMuscleIsIsometricWhenTheTendonCarriesTheProjectedFibreForce) {
  const auto p = variants()[1];
  for (double x : {0.1, 0.14, 0.19})
    for (double a : {0.05, 0.4, 1.0}) {
      const auto g = fm::fiber_geometry(p, x);
      const double fibre = a * p.max_isometric_force_N * fm::force_length(p, g.length_m) + fm::passive_fiber_force(p, g.length_m);
      const double tendon = fibre * g.cos_pennation;
      EXPECT_NEAR(fm::force_ratio(p, tendon, a, x), 1.0, 1e-14);
      EXPECT_NEAR(fm::fiber_shortening_velocity(p, tendon, a, x), 0.0, 1e-14);
      EXPECT_GT(fm::fiber_shortening_velocity(p, 0.9 * tendon, a, x), 0.0);  // concentric
      // The unit along the tendon shortens faster than the fibre: by 1 / cos.
      const double ls = fm::tendon_length_from_force(p, 0.9 * tendon);
      const double u = fm::fiber_shortening_velocity(p, 0.9 * tendon, a, x);
      EXPECT_NEAR(fm::tendon_length_derivative(p, ls, a, ls + x, 0.0), u / g.cos_pennation, 1e-12);
    }
}

TEST(StaticEquilibrium, PennatedPassiveMuscleRestsThere) {
  const auto p = variants()[1];
  // From a short unit to one whose fibres are stretched far into the passive range.
  for (double L : linspace(p.tendon_slack_length_m + 0.06, p.tendon_slack_length_m + 0.26, 9))
    for (double a : {0.0, 0.02, 0.3, 1.0}) {
      const double ls = fm::static_equilibrium_tendon_length(p, L, a);
      EXPECT_NEAR(fm::tendon_length_derivative(p, ls, a, L, 0.0), 0.0, 1e-9) << L << " " << a;
      EXPECT_GT(ls, p.tendon_slack_length_m);
    }
  // Passive force alone holds the tendon taut once the fibres are beyond optimal length.
  const double long_unit = p.tendon_slack_length_m + 1.5 * p.optimal_fiber_length_m;
  const double ls_passive = fm::static_equilibrium_tendon_length(p, long_unit, 0.0);
  auto no_passive = p;
  no_passive.passive_fiber_strain_at_one_norm_force = 0.0;
  EXPECT_GT(fm::tendon_force(p, ls_passive), 10.0 * fm::tendon_force(no_passive, fm::static_equilibrium_tendon_length(no_passive, long_unit, 0.0)));
}
