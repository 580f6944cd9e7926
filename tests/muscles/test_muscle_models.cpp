// The muscle-model seam: each model's derivatives and inverses by the finite-difference twin,
// Thelen's published properties, the registry, and a deliberately wrong model the twin catches.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <stdexcept>

#include "flatsos/muscles/degroote_fregly2016_muscle.hpp"
#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/muscles/muscle_model.hpp"
#include "example_muscles.hpp"
#include "flatsos/muscles/muscle_model_check.hpp"
#include "flatsos/muscles/richter_warner_muscle.hpp"
#include "flatsos/muscles/thelen2003_muscle.hpp"

namespace fm = flatsos::muscles;

namespace {

fm::MuscleParameters muscle(const std::string& model) { return flatsos::test::muscle_with_defaults(model); }

// Richter & Warner's laws with a tendon slope 0.1 % too steep.
class WrongSlope final : public fm::MuscleModel {
 public:
  std::string name() const override { return "wrong"; }
  void validate(const fm::MuscleParameters& p) const override { base_.validate(p); }
  void setDefaults(fm::MuscleParameters& p) const override { base_.setDefaults(p); }
  std::string slopeJumps() const override { return {}; }
  fm::CurveJet tendonForce(const fm::MuscleParameters& p, double l) const override {
    fm::CurveJet j = base_.tendonForce(p, l);
    j.slope *= 1.001;
    return j;
  }
  double tendonForceThirdDerivative(const fm::MuscleParameters& p, double l) const override {
    return base_.tendonForceThirdDerivative(p, l);
  }
  double tendonLengthFromForce(const fm::MuscleParameters& p, double f) const override {
    return base_.tendonLengthFromForce(p, f);
  }
  fm::CurveJet activeForceLength(const fm::MuscleParameters& p, double l) const override {
    return base_.activeForceLength(p, l);
  }
  fm::CurveJet passiveFiberForce(const fm::MuscleParameters& p, double l) const override {
    return base_.passiveFiberForce(p, l);
  }
  fm::CurveJet forceVelocity(const fm::MuscleParameters& p, double u) const override { return base_.forceVelocity(p, u); }
  double forceVelocityInverse(const fm::MuscleParameters& p, double z) const override {
    return base_.forceVelocityInverse(p, z);
  }
  double forceRatioExactUpperBound(const fm::MuscleParameters& p) const override {
    return base_.forceRatioExactUpperBound(p);
  }
  fm::CurveJet fiberVelocityFromForceRatio(const fm::MuscleParameters& p, double z) const override {
    return base_.fiberVelocityFromForceRatio(p, z);
  }
  fm::ActivationRate activationRate(const fm::MuscleParameters& p, double n, double a) const override {
    return base_.activationRate(p, n, a);
  }
  fm::ExcitationFromActivation excitationFromActivation(const fm::MuscleParameters& p, double a,
                                                        double r) const override {
    return base_.excitationFromActivation(p, a, r);
  }
  fm::ExcitationBoundMargins excitationBoundMargins(const fm::MuscleParameters& p, double a, double r) const override {
    return base_.excitationBoundMargins(p, a, r);
  }

 private:
  fm::RichterWarnerMuscle base_;
};

}  // namespace

TEST(MuscleModels, RichterWarnerPassesTheFiniteDifferenceTwin) {
  fm::MuscleParameters p = muscle("richter_warner");
  const fm::MuscleModelCheck plain = fm::check_muscle_model(p);
  EXPECT_TRUE(plain.ok()) << plain.summary();
  p.passive_fiber_strain_at_one_norm_force = 0.6;
  p.pennation_angle_at_optimal_rad = 0.2;
  const fm::MuscleModelCheck passive = fm::check_muscle_model(p);
  EXPECT_TRUE(passive.ok()) << passive.summary();
  EXPECT_GT(passive.checked, 2000);
  EXPECT_LT(passive.skipped, passive.checked / 50);
}

TEST(MuscleModels, Thelen2003PassesTheFiniteDifferenceTwin) {
  const fm::MuscleModelCheck check = fm::check_muscle_model(muscle("thelen2003"));
  EXPECT_TRUE(check.ok()) << check.summary();
  EXPECT_LT(check.skipped, check.checked / 50);
}

TEST(MuscleModels, DeGrooteFregly2016PassesTheFiniteDifferenceTwin) {
  fm::MuscleParameters p = muscle("degroote_fregly2016");
  const fm::MuscleModelCheck plain = fm::check_muscle_model(p);
  EXPECT_TRUE(plain.ok()) << plain.summary();
  EXPECT_LT(plain.skipped, plain.checked / 50);
  // The steep switch OpenSim recommends (b = 10), a wider active curve and pennation.
  p.activation_dynamics_smoothing = 10.0;
  p.force_length_width = 1.5;
  p.pennation_angle_at_optimal_rad = 0.2;
  const fm::MuscleModelCheck steep = fm::check_muscle_model(p);
  EXPECT_TRUE(steep.ok()) << steep.summary();
}

TEST(MuscleModels, TheTwinCatchesAWrongDerivative) {
  fm::MuscleParameters p = muscle("richter_warner");
  p.model = std::make_shared<WrongSlope>();
  const fm::MuscleModelCheck check = fm::check_muscle_model(p);
  ASSERT_FALSE(check.ok());
  int slopes = 0;
  for (const fm::MuscleModelMismatch& m : check.mismatches) {
    slopes += m.quantity == "tendonForce.slope";
    // The wrong slope also differs from the differences of itself that the curvature meets.
    EXPECT_TRUE(m.quantity == "tendonForce.slope" || m.quantity == "tendonForce.curvature") << m.quantity;
  }
  EXPECT_GT(slopes, 20);
}

TEST(MuscleModels, TheRegistryNamesEveryModelAndRejectsOthers) {
  for (const std::string& name : fm::muscle_model_names()) EXPECT_EQ(fm::muscle_model_named(name)->name(), name);
  EXPECT_EQ(fm::muscle_model_named("richter_warner"), fm::default_muscle_model());
  try {
    fm::muscle_model_named("Thelen2003Muscle");
    FAIL() << "an unknown name was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("thelen2003"), std::string::npos) << e.what();
  }
  fm::MuscleParameters p = muscle("thelen2003");
  p.model = nullptr;
  EXPECT_THROW(fm::validate(p), std::invalid_argument);
}

TEST(Thelen2003, TendonCarriesMaxIsometricForceAtItsStrainAndIsC1AtTheToe) {
  for (const double e0 : {0.04, 0.033}) {  // OpenSim's default and arm26's
    fm::MuscleParameters p = muscle("thelen2003");
    p.tendon_strain_at_max_force = e0;
    const double slack = p.tendon_slack_length_m, fmax = p.max_isometric_force_N;
    EXPECT_NEAR(fm::tendon_force(p, slack * (1.0 + e0)), fmax, 1e-12 * fmax);
    // The toe ends at 0.33 Fmax near Thelen's rounded 0.609 e0, with the linear slope near his
    // 1.712 / e0 (OpenSim: 0.6086 e0 and 42.797 at e0 = 0.04).
    const double toe_strain = 99.0 * e0 * std::exp(3.0) / (166.0 * std::exp(3.0) - 67.0);
    EXPECT_NEAR(toe_strain / e0, 0.6086, 1e-4);
    const double toe_end = slack * (1.0 + toe_strain), h = 1e-9 * slack;
    EXPECT_NEAR(fm::tendon_force(p, toe_end), 0.33 * fmax, 1e-9 * fmax);
    EXPECT_NEAR(fm::tendon_force_derivative(p, toe_end + h) * slack / fmax * e0, 1.712, 2e-4);
    EXPECT_NEAR(fm::tendon_force_derivative(p, toe_end - h) / fm::tendon_force_derivative(p, toe_end + h), 1.0, 1e-6);
    EXPECT_EQ(fm::tendon_force(p, slack), 0.0);
  }
}

TEST(Thelen2003, ForceVelocityHasThelensShape) {
  const fm::MuscleParameters p = muscle("thelen2003");
  const double vmax = p.max_shortening_velocity_m_per_s();
  EXPECT_DOUBLE_EQ(fm::force_velocity(p, 0.0), 1.0);
  EXPECT_NEAR(fm::force_velocity(p, vmax), 0.0, 1e-15);
  // Beyond 0.95 Flen (and below 0) the relation continues linearly, as OpenSim computes it.
  const double z_lin = 0.95 * p.max_eccentric_force_ratio;
  const double u_lin = fm::force_velocity_inverse(p, z_lin);
  EXPECT_NEAR(fm::force_velocity(p, 2.0 * u_lin) - z_lin, u_lin * fm::force_velocity_derivative(p, u_lin - 1e-12), 1e-12);
  EXPECT_NEAR(fm::force_velocity(p, 1.5 * vmax), 0.5 * vmax * fm::force_velocity_derivative(p, vmax + 1e-12), 1e-12);
  // Thelen's eccentric b is (2 + 2 / Af) a f, twice the concentric a f (1 + 1 / Af) at z = 1:
  // the curve's slope doubles across isometric.
  EXPECT_NEAR(fm::force_velocity_derivative(p, -1e-12) / fm::force_velocity_derivative(p, 0.0), 2.0, 1e-9);
  // Half of Vmax concentric: z = Af (1 - 0.5) / (Af + 0.5) = 1/6 at Af = 0.25.
  EXPECT_NEAR(fm::force_velocity(p, 0.5 * vmax), 1.0 / 6.0, 1e-14);
}

// OpenSim's Thelen2003Muscle computes the normalized lengthening velocity from F = fse / cos - fpe
// and A = a fal, with k = 0.25 + 0.75 a, c = 2 + 2 / Af, F0 = 0.95 Flen A (Thelen 2003 with
// OpenSim's extensions), written out here independently of the model's code:
namespace {
double opensim_thelen_lengthening_velocity(double F, double A, double a, double af, double flen) {
  const double k = 0.25 + 0.75 * a, c = 2.0 + 2.0 / af, f0 = 0.95 * flen * A;
  if (F <= 0.0) return -k + k * (1.0 + 1.0 / af) * F / A;
  if (F <= A) return k * (F - A) / (A + F / af);
  if (F < f0) return k * (F - A) * (flen - 1.0) / (c * (flen * A - F));
  const double b0 = c * (flen * A - f0) / (flen - 1.0), v0 = k * (f0 - A) / b0;
  const double s0 = k / b0 + k * (f0 - A) * c / ((flen - 1.0) * b0 * b0);
  return v0 + s0 * (F - f0);
}
}  // namespace

TEST(Thelen2003, TheFibreVelocityIsOpenSims) {
  const fm::MuscleParameters p = muscle("thelen2003");
  const double lopt = p.optimal_fiber_length_m, fmax = p.max_isometric_force_N;
  for (double a : {0.01, 0.05, 0.3, 1.0})
    for (double ratio : {-0.1, 0.0, 0.2, 0.7, 1.0, 1.2, 1.32, 1.36, 1.6}) {
      // At the optimal length, unpennated: fal = 1, no passive force, F = the tendon's force.
      const double F = ratio * a * fmax;
      const double expected = -opensim_thelen_lengthening_velocity(ratio, 1.0, a, p.hill_constant,
                                                                     p.max_eccentric_force_ratio) *
                              p.max_shortening_velocity_m_per_s();
      EXPECT_NEAR(fm::fiber_shortening_velocity(p, F, a, lopt), expected, 1e-12 * lopt) << a << " " << ratio;
    }
}

TEST(Thelen2003, ActivationDynamicsAreOpenSimsFirstOrderModel) {
  const fm::MuscleParameters p = muscle("thelen2003");
  // Activating from 0.5 at n = 1: tau = 0.015 (0.5 + 0.75) = 0.01875 s.
  EXPECT_NEAR(fm::activation_derivative(p, 1.0, 0.5), 0.5 / 0.01875, 1e-12);
  // Deactivating at n = 0 (the excitation is not clamped): tau = 0.05 / 1.25 = 0.04 s.
  EXPECT_NEAR(fm::activation_derivative(p, 0.0, 0.5), -0.5 / 0.04, 1e-12);
  // The activation is clamped to [minimum, 1]: below the minimum it acts as the minimum.
  EXPECT_NEAR(fm::activation_derivative(p, 0.5, 0.001), (0.5 - 0.01) / (0.015 * (0.5 + 1.5 * 0.01)), 1e-9);
  // The excitation's bounds are [minimum, 1] (OpenSim's min_control): deactivating from 0.5
  // faster than n = 0.01 allows, (0.01 - 0.5) / 0.04 = -12.25 /s, needs an excitation below them.
  EXPECT_NEAR(fm::excitation_from_activation(p, 0.5, -12.25).excitation, 0.01, 1e-12);
  EXPECT_LT(fm::excitation_bound_margins(p, 0.5, -12.3).lower, 0.0);
  EXPECT_GT(fm::excitation_bound_margins(p, 0.5, -12.2).lower, 0.0);
  EXPECT_DOUBLE_EQ(p.model->minimumExcitation(p), 0.01);
}

TEST(Thelen2003, DefaultsAreOpenSims) {
  const fm::MuscleParameters p = muscle("thelen2003");
  EXPECT_DOUBLE_EQ(p.force_length_width * p.force_length_width, 0.45);  // KshapeActive
  EXPECT_DOUBLE_EQ(p.max_eccentric_force_ratio, 1.4);                   // Flen
  EXPECT_DOUBLE_EQ(p.activation_time_constant_s, 0.015);
  EXPECT_DOUBLE_EQ(p.deactivation_time_constant_s, 0.05);
  EXPECT_DOUBLE_EQ(p.activation_floor, 0.01);
  EXPECT_DOUBLE_EQ(p.passive_force_length_shape, 5.0);  // KshapePassive
  EXPECT_DOUBLE_EQ(p.passive_fiber_strain_at_one_norm_force, 0.6);
  EXPECT_DOUBLE_EQ(p.tendon_strain_at_max_force, 0.04);
  EXPECT_NO_THROW(fm::validate(p));
}

TEST(DeGrooteFregly2016, CurvesPassThroughOpenSimsPoints) {
  const fm::MuscleParameters p = muscle("degroote_fregly2016");
  const double slack = p.tendon_slack_length_m, fmax = p.max_isometric_force_N, lopt = p.optimal_fiber_length_m;
  const double vmax = p.max_shortening_velocity_m_per_s();
  EXPECT_TRUE(p.model->slopeJumps().empty());
  // Tendon: 0 at slack, Fmax at e0 = 0.049, a compression approaching -0.2 Fmax far below slack.
  EXPECT_EQ(fm::tendon_force(p, slack), 0.0);
  EXPECT_NEAR(fm::tendon_force(p, slack * 1.049), fmax, 1e-12 * fmax);
  EXPECT_NEAR(fm::tendon_force(p, 0.5 * slack), -0.2 * fmax, 1e-6 * fmax);
  // Active force-length: 1 at the optimal length, the curve's other Gaussians small far away.
  EXPECT_NEAR(fm::force_length(p, lopt), 1.0, 1e-12);
  EXPECT_LT(fm::force_length(p, 0.4 * lopt), 0.1);
  EXPECT_LT(fm::force_length(p, 1.8 * lopt), 0.1);
  // Passive: 0 at the model's least fibre length 0.2 Lopt, Fmax at 1 + e0 (e0 = 0.6).
  EXPECT_NEAR(fm::passive_fiber_force(p, 0.2 * lopt), 0.0, 1e-12 * fmax);
  EXPECT_NEAR(fm::passive_fiber_force(p, 1.6 * lopt), fmax, 1e-12 * fmax);
  EXPECT_LT(fm::passive_fiber_force(p, 0.1 * lopt), 0.0);
  // Force-velocity through (-1, 0), (0, 1) and (1, 1.794) in OpenSim's lengthening velocity.
  EXPECT_NEAR(fm::force_velocity(p, vmax), 0.0, 1e-6);
  EXPECT_NEAR(fm::force_velocity(p, 0.0), 1.0, 1e-12);
  EXPECT_NEAR(fm::force_velocity(p, -vmax), 1.794, 5e-4);
  EXPECT_NEAR(p.model->forceRatioExactUpperBound(p), fm::force_velocity(p, -vmax), 1e-15);
}

TEST(DeGrooteFregly2016, ActivationSmoothsThelensTwoTimeConstants) {
  fm::MuscleParameters p = muscle("degroote_fregly2016");
  const double a = 0.5, s = 0.5 + 1.5 * a;
  // OpenSim's default b = 0.1 barely switches: at n = 1 the time constant is close to the mean of
  // T_act s and T_deact / s, weighted by (1 +- tanh(0.05)) / 2.
  const double t = std::tanh(0.1 * 0.5);
  const double expected = ((0.5 + 0.5 * t) / (0.015 * s) + (0.5 - 0.5 * t) * s / 0.060) * 0.5;
  EXPECT_NEAR(fm::activation_derivative(p, 1.0, a), expected, 1e-12 * expected);
  EXPECT_EQ(fm::activation_derivative(p, a, a), 0.0);
  // A steep switch approaches Thelen's first-order model on each side.
  p.activation_dynamics_smoothing = 1e3;
  EXPECT_NEAR(fm::activation_derivative(p, 1.0, a), 0.5 / (0.015 * s), 1e-9);
  EXPECT_NEAR(fm::activation_derivative(p, 0.0, a), -0.5 * s / 0.060, 1e-9);
  // The inverse finds the excitation that gives a rate, at the bounds too.
  for (const double n : {0.0, 0.3, 1.0}) {
    const double rate = fm::activation_derivative(p, n, 0.2);
    EXPECT_NEAR(fm::excitation_from_activation(p, 0.2, rate).excitation, n, 1e-12);
  }
}

TEST(DeGrooteFregly2016, DefaultsAreOpenSims) {
  const fm::MuscleParameters p = muscle("degroote_fregly2016");
  EXPECT_DOUBLE_EQ(p.tendon_strain_at_max_force, 0.049);
  EXPECT_DOUBLE_EQ(p.force_length_width, 1.0);  // active_force_width_scale
  EXPECT_DOUBLE_EQ(p.passive_fiber_strain_at_one_norm_force, 0.6);
  EXPECT_DOUBLE_EQ(p.activation_time_constant_s, 0.015);
  EXPECT_DOUBLE_EQ(p.deactivation_time_constant_s, 0.060);
  EXPECT_DOUBLE_EQ(p.activation_dynamics_smoothing, 0.1);
  EXPECT_NO_THROW(fm::validate(p));
  fm::MuscleParameters narrow = p;
  narrow.force_length_width = 0.5;
  EXPECT_THROW(fm::validate(narrow), std::invalid_argument);
}
