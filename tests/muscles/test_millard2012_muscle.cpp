// OpenSim's Millard2012EquilibriumMuscle behind the muscle-model seam: the finite-difference
// twin, the curves' stated anchor values in SI units, the inverses, the fibre velocity of the
// damped and undamped forward models against OpenSim's equations written out here (from the
// memo, on the curves of millard2012_curves.hpp built independently of the model), the fibre
// floor, the checks that name their field, and the Tug_of_War_Millard muscles.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/muscles/millard2012_muscle.hpp"
#include "flatsos/muscles/muscle_model_check.hpp"

namespace fm = flatsos::muscles;

namespace {

fm::MuscleParameters muscle(std::shared_ptr<const fm::MuscleModel> model) {
  fm::MuscleParameters p;
  p.name = "m";
  p.max_isometric_force_N = 600.0;
  p.optimal_fiber_length_m = 0.11;
  p.tendon_slack_length_m = 0.20;
  p.model = std::move(model);
  p.model->setDefaults(p);
  return p;
}
fm::MuscleParameters default_muscle() { return muscle(fm::muscle_model_named("millard2012")); }

fm::Millard2012MuscleConfiguration undamped() {
  fm::Millard2012MuscleConfiguration c;
  c.fiber_damping = 0.0;
  return c;
}

// Tug_of_War_Millard.osim's muscles (both alike): fL 0.4441 / 0.6259 / 1.8123, shallow slope
// 0.8616, minimum 0; fV at OpenSim's defaults (slopes 0, 0.25, 5, 0, 0.15; fmax 1.4); passive
// strains 0 / 0.6 with the optional properties empty; tendon strain 0.049, optional empty.
fm::Millard2012CurveParameters tug_of_war_curves() {
  fm::Millard2012CurveParameters c;
  c.active_force_length = {0.4441, 0.6259, 1.8123, 0.8616, 0.0};
  c.fiber_force_length.strain_at_zero_force = 0.0;
  c.fiber_force_length.strain_at_one_norm_force = 0.6;
  c.tendon_force_length.strain_at_one_norm_force = 0.049;
  return c;
}
fm::MuscleParameters tug_of_war_muscle() {
  fm::MuscleParameters p = muscle(std::make_shared<fm::Millard2012Muscle>(tug_of_war_curves()));
  p.name = "RightMuscle";
  p.max_isometric_force_N = 1000.0;
  p.optimal_fiber_length_m = 0.1;
  p.tendon_slack_length_m = 0.2;
  return p;
}

// OpenSim's damped balance (memo): the normalised lengthening velocity v with
//   (a fL fV(v) + fPE + beta v) cos(phi) = fSE,
// increasing in v with slope >= beta cos(phi); bracketed, then Newton kept in the bracket.
double opensim_damped_lengthening(const fm::QuinticBezierCurve& fv, double a, double fl, double fpe, double fse,
                                  double beta, double cos_phi) {
  const auto residual = [&](double v) { return (a * fl * fv.value(v) + fpe + beta * v) * cos_phi - fse; };
  double lo = -1.0, hi = 1.0;
  while (residual(lo) > 0.0) lo -= 2.0 * (hi - lo);
  while (residual(hi) < 0.0) hi += 2.0 * (hi - lo);
  double v = 0.5 * (lo + hi);
  for (int k = 0; k < 200 && hi - lo > 1e-15; ++k) {
    const double r = residual(v);
    if (r == 0.0) break;
    (r < 0.0 ? lo : hi) = v;
    const double next = v - r / ((a * fl * fv.evaluate(v).first + beta) * cos_phi);
    v = next > lo && next < hi ? next : 0.5 * (lo + hi);
  }
  return v;
}

// One state of a muscle and what OpenSim's curves say about it (independent of the model).
struct State {
  double activation, fiber_length_m, tendon_force_N;
};
struct Expected {
  double shortening_velocity_m_per_s, lengthening, active_factor;
};
Expected opensim_damped(const fm::MuscleParameters& p, const fm::Millard2012Curves& curves, const State& s) {
  const double lopt = p.optimal_fiber_length_m, h = p.fiber_thickness_m();
  const double l = s.fiber_length_m / lopt, cos_phi = std::sqrt(s.fiber_length_m * s.fiber_length_m - h * h) / s.fiber_length_m;
  const double a = std::clamp(s.activation, p.activation_floor, 1.0);
  const double fl = curves.active_force_length.value(l);
  const double v = opensim_damped_lengthening(curves.force_velocity, a, fl, curves.fiber_force_length.value(l),
                                              s.tendon_force_N / p.max_isometric_force_N, p.fiber_damping, cos_phi);
  return {-v * p.max_shortening_velocity_m_per_s(), v, a * fl};
}
double along_tendon(const fm::MuscleParameters& p, double fiber_length_m) {
  const double h = p.fiber_thickness_m();
  return std::sqrt(fiber_length_m * fiber_length_m - h * h);
}

}  // namespace

TEST(Millard2012Muscle, PassesTheFiniteDifferenceTwin) {
  fm::MuscleParameters p = default_muscle();
  const fm::MuscleModelCheck plain = fm::check_muscle_model(p);
  EXPECT_TRUE(plain.ok()) << plain.summary();
  EXPECT_LT(plain.skipped, plain.checked / 50) << plain.summary();
  p.pennation_angle_at_optimal_rad = 0.3;
  const fm::MuscleModelCheck pennated = fm::check_muscle_model(p);
  EXPECT_TRUE(pennated.ok()) << pennated.summary();
  fm::MuscleParameters classic = muscle(std::make_shared<fm::Millard2012Muscle>(fm::Millard2012CurveParameters{}, undamped()));
  const fm::MuscleModelCheck undamped_check = fm::check_muscle_model(classic);
  EXPECT_TRUE(undamped_check.ok()) << undamped_check.summary();
  const fm::MuscleModelCheck tug = fm::check_muscle_model(tug_of_war_muscle());
  EXPECT_TRUE(tug.ok()) << tug.summary();
}

TEST(Millard2012Muscle, CurvesPassThroughTheirStatedPointsInSiUnits) {
  const fm::MuscleParameters p = default_muscle();
  const double slack = p.tendon_slack_length_m, fmax = p.max_isometric_force_N, lopt = p.optimal_fiber_length_m;
  const double vmax = p.max_shortening_velocity_m_per_s();
  // Tendon: 0 at and below slack, Fmax at strain 0.049 with stiffness 1.375 / 0.049 Fmax / slack,
  // 2/3 Fmax at the toe's end (on the linear part through Fmax).
  EXPECT_EQ(fm::tendon_force(p, slack), 0.0);
  EXPECT_EQ(fm::tendon_force(p, 0.9 * slack), 0.0);
  EXPECT_NEAR(fm::tendon_force(p, 1.049 * slack), fmax, 1e-12 * fmax);
  EXPECT_NEAR(fm::tendon_force_derivative(p, 1.049 * slack), 1.375 / 0.049 * fmax / slack, 1e-9 * fmax / slack);
  const double toe_end = slack * (1.049 - (1.0 / 3.0) * 0.049 / 1.375);
  EXPECT_NEAR(fm::tendon_force(p, toe_end), 2.0 / 3.0 * fmax, 1e-12 * fmax);
  // Active: 1 at Lopt with slope 0; 0 (the damped minimum) from 0.4441 Lopt down and 1.8123 up.
  EXPECT_NEAR(fm::force_length(p, lopt), 1.0, 1e-15);
  EXPECT_NEAR(fm::force_length_derivative(p, lopt), 0.0, 1e-12 / lopt);
  EXPECT_EQ(fm::force_length(p, 0.4441 * lopt), 0.0);
  EXPECT_EQ(fm::force_length(p, 0.3 * lopt), 0.0);
  EXPECT_EQ(fm::force_length(p, 1.9 * lopt), 0.0);
  // Passive: 0 up to Lopt, Fmax at 1.7 Lopt with stiffness 2 / 0.7 Fmax / Lopt.
  EXPECT_EQ(fm::passive_fiber_force(p, lopt), 0.0);
  EXPECT_NEAR(fm::passive_fiber_force(p, 1.7 * lopt), fmax, 1e-12 * fmax);
  EXPECT_NEAR(fm::passive_fiber_force_derivative(p, 1.7 * lopt), 2.0 / 0.7 * fmax / lopt, 1e-9 * fmax / lopt);
  // Force-velocity in flatsos' shortening u: g(0) = 1 with slope -5 / Vmax (isometric_slope 5),
  // 0 from Vmax on, 1.4 from -Vmax on (the damped curve is flat beyond), slopes 0.25 and 0.15
  // at 0.9 Vmax either side.
  EXPECT_NEAR(fm::force_velocity(p, 0.0), 1.0, 1e-15);
  EXPECT_NEAR(fm::force_velocity_derivative(p, 0.0), -5.0 / vmax, 1e-12 / vmax);
  EXPECT_NEAR(fm::force_velocity(p, vmax), 0.0, 1e-15);
  EXPECT_EQ(fm::force_velocity(p, 1.5 * vmax), 0.0);
  EXPECT_NEAR(fm::force_velocity(p, -vmax), 1.4, 1e-15);
  EXPECT_EQ(fm::force_velocity(p, -2.0 * vmax), 1.4);
  EXPECT_NEAR(fm::force_velocity_derivative(p, 0.9 * vmax), -0.25 / vmax, 1e-12 / vmax);
  EXPECT_NEAR(fm::force_velocity_derivative(p, -0.9 * vmax), -0.15 / vmax, 1e-12 / vmax);
}

TEST(Millard2012Muscle, InversesRoundTrip) {
  const fm::MuscleParameters p = default_muscle();
  const double slack = p.tendon_slack_length_m, vmax = p.max_shortening_velocity_m_per_s();
  for (double strain : {1e-4, 0.01, 0.03, 0.049, 0.1}) {
    const double length = slack * (1.0 + strain);
    EXPECT_NEAR(fm::tendon_length_from_force(p, fm::tendon_force(p, length)), length, 1e-13 * slack) << strain;
  }
  EXPECT_THROW(fm::tendon_length_from_force(p, 0.0), std::domain_error);
  for (double x = -0.99; x < 1.0; x += 0.0625) {
    const double u = -x * vmax;
    EXPECT_NEAR(fm::force_velocity_inverse(p, fm::force_velocity(p, u)), u, 1e-11 * vmax) << x;
    EXPECT_NEAR(fm::fiber_velocity_from_force_ratio(p, fm::force_velocity(p, u)), u, 1e-11 * vmax) << x;
  }
  // Damped: g is one to one only on (0, fmax); the forward model's inverse continues beyond
  // with fV slope sqrt(eps), finite and decreasing.
  EXPECT_THROW(fm::force_velocity_inverse(p, 0.0), std::domain_error);
  EXPECT_THROW(fm::force_velocity_inverse(p, 1.4), std::domain_error);
  const double root_eps = std::sqrt(std::numeric_limits<double>::epsilon());
  EXPECT_DOUBLE_EQ(fm::fiber_velocity_from_force_ratio(p, 0.0), vmax);
  EXPECT_DOUBLE_EQ(fm::fiber_velocity_from_force_ratio(p, -root_eps), 2.0 * vmax);
  EXPECT_DOUBLE_EQ(fm::fiber_velocity_from_force_ratio(p, 1.4 + 2.0 * root_eps), -3.0 * vmax);
  EXPECT_DOUBLE_EQ(fm::fiber_velocity_from_force_ratio_derivative(p, -1.0), -vmax / root_eps);
  double previous = std::numeric_limits<double>::infinity();
  for (double z = -0.5; z < 2.0; z += 0.01) {
    const double u = fm::fiber_velocity_from_force_ratio(p, z);
    EXPECT_TRUE(std::isfinite(u) && std::isfinite(fm::fiber_velocity_from_force_ratio_derivative(p, z))) << z;
    EXPECT_LT(u, previous) << z;
    previous = u;
  }
  // The exact bound is the double below fmax: u <= -Vmax all give fmax.
  EXPECT_EQ(fm::force_ratio_exact_upper_bound(p), std::nextafter(1.4, 0.0));
}

TEST(Millard2012Muscle, DampedFibreVelocityIsOpenSimsBalance) {
  const fm::Millard2012Curves curves =
      fm::millard2012_curves(fm::millard2012_muscle_curve_parameters({}, fm::Millard2012MuscleConfiguration{}));
  const double root_eps = std::sqrt(std::numeric_limits<double>::epsilon());
  for (double pennation : {0.0, 0.35}) {
    fm::MuscleParameters p = default_muscle();
    p.pennation_angle_at_optimal_rad = pennation;
    const double lopt = p.optimal_fiber_length_m, fmax = p.max_isometric_force_N;
    const double vmax = p.max_shortening_velocity_m_per_s(), beta = p.fiber_damping;
    int inside = 0, beyond = 0;
    for (double a : {0.0, 0.01, 0.2, 0.7, 1.0})
      for (double l : {0.5, 0.8, 1.0, 1.3, 1.6}) {
        // Tendon forces on a grid, and those that balance chosen velocities inside +-Vmax.
        std::vector<double> forces = {0.01 * fmax, 0.3 * fmax, 0.9 * fmax, 1.3 * fmax, 1.8 * fmax};
        const double x = l, h = p.fiber_thickness_m() / lopt, cos_phi = std::sqrt(x * x - h * h) / x;
        const double a_eff = std::max(a, p.activation_floor), fl = curves.active_force_length.value(x);
        for (double v : {-0.97, -0.6, -0.2, 0.0, 0.3, 0.7, 0.97}) {
          const double F = (a_eff * fl * curves.force_velocity.value(v) + curves.fiber_force_length.value(x) + beta * v) *
                           cos_phi * fmax;
          if (F > 0.0) forces.push_back(F);
        }
        for (double F : forces) {
          const State s{a, l * lopt, F};
          const Expected e = opensim_damped(p, curves, s);
          const double u = fm::fiber_shortening_velocity(p, F, a, along_tendon(p, s.fiber_length_m));
          if (std::abs(e.lengthening) < 1.0) {
            ++inside;
            EXPECT_NEAR(u, e.shortening_velocity_m_per_s, 1e-10 * vmax) << a << " " << l << " " << F;
            continue;
          }
          // Beyond +-Vmax flatsos' continuation adds an active force of fV slope sqrt(eps): the
          // velocity moves by at most sqrt(eps) a fL / beta (|v| - 1) Vmax. And the shared
          // solver resolves z to 1e-15 (1 + |z|), which u = V(z) multiplies by Vmax / sqrt(eps).
          ++beyond;
          const double model = root_eps * e.active_factor / beta * (std::abs(e.lengthening) - 1.0);
          const double resolution = 1e-15 * (1.0 + 1.4) / root_eps;
          EXPECT_NEAR(u, e.shortening_velocity_m_per_s, (model + resolution) * vmax) << a << " " << l << " " << F;
        }
      }
    EXPECT_GT(inside, 100);
    EXPECT_GT(beyond, 30);
  }
}

TEST(Millard2012Muscle, UndampedFibreVelocityIsOpenSimsInverseCurve) {
  fm::MuscleParameters p = muscle(std::make_shared<fm::Millard2012Muscle>(fm::Millard2012CurveParameters{}, undamped()));
  EXPECT_EQ(p.fiber_damping, 0.0);
  EXPECT_EQ(fm::force_ratio_exact_upper_bound(p), std::numeric_limits<double>::infinity());
  const fm::Millard2012Curves curves = fm::millard2012_curves(fm::millard2012_muscle_curve_parameters({}, undamped()));
  const double lopt = p.optimal_fiber_length_m, fmax = p.max_isometric_force_N, vmax = p.max_shortening_velocity_m_per_s();
  // fV = (fSE / cos - fPE) / (a fL), v = fvInv(fV) (memo), unpennated at the lengths below.
  for (double a : {0.01, 0.3, 1.0})
    for (double l : {0.5, 1.0, 1.5})
      for (double force : {0.0, 0.2, 1.0, 1.6}) {
        const double F = force * fmax;
        const double ratio = (force - curves.fiber_force_length.value(l)) / (a * curves.active_force_length.value(l));
        const double expected = -vmax * curves.force_velocity_inverse.value(ratio);
        EXPECT_NEAR(fm::fiber_shortening_velocity(p, F, a, l * lopt), expected, 1e-12 * vmax * (1.0 + std::abs(expected / vmax)))
            << a << " " << l << " " << force;
      }
  // The classic model's active curve keeps a minimum of 0.1, and OpenSim's check on the floor.
  EXPECT_NEAR(fm::force_length(p, 0.3 * lopt), 0.1, 1e-15);
  p.activation_floor = 0.005;
  EXPECT_THROW(fm::validate(p), std::invalid_argument);
}

TEST(Millard2012Muscle, HoldsTheFibreAtItsMinimumLength) {
  fm::MuscleParameters p = default_muscle();
  const double lopt = p.optimal_fiber_length_m;
  // Unpennated: the active curve's start, 0.4441 Lopt (OpenSim's default 0.47 - 0.0259).
  EXPECT_NEAR(p.model->minimumFiberLength(p), (0.47 - 0.0259) * lopt, 1e-15);
  // Steeply pennated: the fibre at the maximum angle acos(0.1), h / sin = Lopt sin(phi0) / sqrt(0.99).
  p.pennation_angle_at_optimal_rad = 0.8;
  EXPECT_NEAR(p.model->minimumFiberLength(p), lopt * std::sin(0.8) / std::sqrt(0.99), 1e-15);
  // The damped curve's fL is 0 at the minimum, so there a tendon under tension only lengthens
  // the fibre; the classic model's fL is 0.1 there and can shorten it.
  p = muscle(std::make_shared<fm::Millard2012Muscle>(fm::Millard2012CurveParameters{}, undamped()));
  const double minimum = p.model->minimumFiberLength(p), fmax = p.max_isometric_force_N;
  const double pulling = 0.01 * fmax, path_rate = -0.3;
  const double tendon = fm::tendon_length_from_force(p, pulling);
  ASSERT_GT(fm::fiber_shortening_velocity(p, pulling, 1.0, 1.001 * minimum), 0.0);  // just above: it shortens
  // At the minimum a fibre that would shorten holds: the tendon takes the path's motion and
  // nothing else moves it (a path length a little inside, so that rounding L - L_S cannot
  // leave the floor).
  EXPECT_EQ(fm::fiber_shortening_velocity(p, pulling, 1.0, minimum), 0.0);
  const double at = tendon + (1.0 - 1e-9) * minimum;
  EXPECT_EQ(fm::tendon_length_derivative(p, tendon, 1.0, at, path_rate), path_rate);
  const fm::TendonLengthDerivativePartials held = fm::tendon_length_derivative_partials(p, tendon, 1.0, at);
  EXPECT_EQ(held.d_tendon_length_per_s, 0.0);
  EXPECT_EQ(held.d_activation_m_per_s, 0.0);
  EXPECT_EQ(held.d_musculotendon_length_per_s, 0.0);
  // Below it too, even lengthening; at it and lengthening, it moves.
  EXPECT_EQ(fm::fiber_shortening_velocity(p, 2.0 * fmax, 1.0, 0.99 * minimum), 0.0);
  EXPECT_LT(fm::fiber_shortening_velocity(p, 2.0 * fmax, 1.0, minimum), 0.0);
  // Other models have no such floor.
  fm::MuscleParameters thelen = p;
  thelen.model = fm::muscle_model_named("thelen2003");
  thelen.model->setDefaults(thelen);
  EXPECT_EQ(thelen.model->minimumFiberLength(thelen), 0.0);
  EXPECT_GT(fm::fiber_shortening_velocity(thelen, pulling, 1.0, 0.3 * lopt), 0.0);
}

TEST(Millard2012Muscle, ChecksNameTheirField) {
  const auto expect_rejected = [](const fm::MuscleParameters& p, const std::string& field) {
    try {
      fm::validate(p);
      ADD_FAILURE() << field << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  const fm::MuscleParameters good = default_muscle();
  EXPECT_NO_THROW(fm::validate(good));
  fm::MuscleParameters p = good;
  p.fiber_damping = 0.0;  // the damped curves with the undamped balance
  expect_rejected(p, "fiber_damping");
  p.fiber_damping = 0.0005;  // OpenSim would treat it as 0
  expect_rejected(p, "fiber_damping");
  p = good;
  p.fiber_damping = 0.05;  // another damping of the same kind: the same curves
  EXPECT_NO_THROW(fm::validate(p));
  p = good;
  p.tendon_strain_at_max_force = 0.04;
  expect_rejected(p, "tendon_strain_at_max_force");
  p = good;
  p.passive_fiber_strain_at_one_norm_force = 0.6;
  expect_rejected(p, "passive_fiber_strain_at_one_norm_force");
  fm::MuscleParameters classic = muscle(std::make_shared<fm::Millard2012Muscle>(fm::Millard2012CurveParameters{}, undamped()));
  classic.fiber_damping = 0.1;
  expect_rejected(classic, "fiber_damping");
  // Construction: a rigid tendon, a maximum pennation outside [0, pi/2], a bad curve property.
  fm::Millard2012MuscleConfiguration rigid;
  rigid.ignore_tendon_compliance = true;
  EXPECT_THROW(fm::Millard2012Muscle({}, rigid), std::invalid_argument);
  EXPECT_THROW(fm::Millard2012Muscle({}, {}, 2.0), std::invalid_argument);
  fm::Millard2012CurveParameters bad;
  bad.force_velocity.concentric_slope_near_vmax = 0.0;
  EXPECT_THROW(fm::Millard2012Muscle{bad}, std::invalid_argument);
}

TEST(Millard2012Muscle, DefaultsAndActivationAreOpenSims) {
  const fm::MuscleParameters p = default_muscle();
  EXPECT_EQ(p.model->name(), "millard2012");
  EXPECT_DOUBLE_EQ(p.max_shortening_velocity_in_optimal_lengths_per_s, 10.0);
  EXPECT_DOUBLE_EQ(p.activation_time_constant_s, 0.010);
  EXPECT_DOUBLE_EQ(p.deactivation_time_constant_s, 0.040);
  EXPECT_DOUBLE_EQ(p.activation_floor, 0.01);
  EXPECT_DOUBLE_EQ(p.fiber_damping, 0.1);
  EXPECT_DOUBLE_EQ(p.tendon_strain_at_max_force, 0.049);
  EXPECT_DOUBLE_EQ(p.passive_fiber_strain_at_one_norm_force, 0.7);
  EXPECT_DOUBLE_EQ(p.model->minimumExcitation(p), 0.01);
  // Activating from 0.5 at n = 1: tau = 0.010 (0.5 + 0.75) s; deactivating at n = 0:
  // tau = 0.040 / 1.25 s; below the minimum activation the dynamics read the minimum.
  EXPECT_NEAR(fm::activation_derivative(p, 1.0, 0.5), 0.5 / 0.0125, 1e-12);
  EXPECT_NEAR(fm::activation_derivative(p, 0.0, 0.5), -0.5 / 0.032, 1e-12);
  EXPECT_NEAR(fm::activation_derivative(p, 0.5, 0.001), (0.5 - 0.01) / (0.010 * (0.5 + 1.5 * 0.01)), 1e-9);
  EXPECT_NE(p.model->slopeJumps().find("activation"), std::string::npos);
}

TEST(Millard2012Muscle, TugOfWarMusclesAreOpenSims) {
  const fm::MuscleParameters p = tug_of_war_muscle();
  EXPECT_NO_THROW(fm::validate(p));
  const double lopt = p.optimal_fiber_length_m, fmax = p.max_isometric_force_N;
  // lmin = 0.4441 Lopt = 0.04441 m (phi0 = 0).
  EXPECT_NEAR(p.model->minimumFiberLength(p), 0.04441, 1e-15);
  // Passive Fmax at 1.6 Lopt with the default stiffness 2 / 0.6; active 0 below 0.4441 Lopt.
  EXPECT_NEAR(fm::passive_fiber_force(p, 1.6 * lopt), fmax, 1e-12 * fmax);
  EXPECT_NEAR(fm::passive_fiber_force_derivative(p, 1.6 * lopt), 2.0 / 0.6 * fmax / lopt, 1e-9 * fmax / lopt);
  EXPECT_EQ(fm::force_length(p, 0.44 * lopt), 0.0);
  EXPECT_NEAR(fm::tendon_force(p, 1.049 * p.tendon_slack_length_m), fmax, 1e-12 * fmax);
  // Its damped fibre velocity is OpenSim's: tendon forces that balance chosen velocities.
  const fm::Millard2012Curves curves = fm::millard2012_curves(
      fm::millard2012_muscle_curve_parameters(tug_of_war_curves(), fm::Millard2012MuscleConfiguration{}));
  const double vmax = p.max_shortening_velocity_m_per_s();
  for (double a : {0.05, 1.0})
    for (double l : {0.5, 0.7, 1.0, 1.4})
      for (double v : {-0.9, -0.3, 0.0, 0.5, 0.95}) {
        const double F = (a * curves.active_force_length.value(l) * curves.force_velocity.value(v) +
                          curves.fiber_force_length.value(l) + 0.1 * v) * fmax;
        if (!(F > 0.0)) continue;
        EXPECT_NEAR(opensim_damped(p, curves, {a, l * lopt, F}).lengthening, v, 1e-12);
        EXPECT_NEAR(fm::fiber_shortening_velocity(p, F, a, l * lopt), -v * vmax, 1e-10 * vmax) << a << " " << l << " " << v;
      }
}
