#include "flatsos/muscles/thelen2003_muscle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "first_order_activation.hpp"
#include "parameter_checks.hpp"
#include "shared_curves.hpp"

namespace flatsos::muscles {
namespace {

// Thelen's tendon: an exponential toe up to Ftoe = 0.33 Fmax (shape kToe = 3), then linear. Where
// the toe ends (eToe) and the linear slope (klin) follow, as in OpenSim, from F(e0) = Fmax and a
// continuous slope at eToe: eToe = 99 e0 e^3 / (166 e^3 - 67) (Thelen's rounded 0.609 e0),
// klin = 0.67 / (e0 - eToe) (1.712 / e0).
constexpr double kToeForce = 0.33;
constexpr double kToeShape = 3.0;
// OpenSim's fv_linear_extrap_threshold: beyond this fraction of Flen the inverse of g continues
// linearly.
constexpr double kLinearExtrapolationThreshold = 0.95;

struct Tendon {
  double toe_strain, linear_stiffness, toe_scale;  // toe_scale = Ftoe / (exp(kToe) - 1)
};
Tendon tendon_constants(const MuscleParameters& p) {
  const double e0 = p.tendon_strain_at_max_force, e3 = std::exp(kToeShape);
  const double toe_strain = 99.0 * e0 * e3 / (166.0 * e3 - 67.0);
  return {toe_strain, (1.0 - kToeForce) / (e0 - toe_strain), kToeForce / std::expm1(kToeShape)};
}

// Normalized shortening velocity u / Vmax from the force ratio z on the exact branches.
double velocity_exact(const MuscleParameters& p, double z) {
  const double af = p.hill_constant, flen = p.max_eccentric_force_ratio;
  if (z <= 1.0) return (1.0 - z) / (1.0 + z / af);
  return -(z - 1.0) * (flen - 1.0) / ((2.0 + 2.0 / af) * (flen - z));
}
double velocity_exact_slope(const MuscleParameters& p, double z) {
  const double af = p.hill_constant, flen = p.max_eccentric_force_ratio;
  if (z <= 1.0) {
    const double den = 1.0 + z / af;
    return -(1.0 + 1.0 / af) / (den * den);
  }
  const double gap = flen - z;
  return -(flen - 1.0) * (flen - 1.0) / ((2.0 + 2.0 / af) * gap * gap);
}

}  // namespace

void Thelen2003Muscle::setDefaults(MuscleParameters& p) const {
  p.tendon_strain_at_max_force = 0.04;
  p.force_length_width = std::sqrt(0.45);
  p.passive_fiber_strain_at_one_norm_force = 0.6;
  p.passive_force_length_shape = 5.0;
  p.hill_constant = 0.25;
  p.max_eccentric_force_ratio = 1.4;
  p.max_shortening_velocity_in_optimal_lengths_per_s = 10.0;
  p.activation_time_constant_s = 0.015;
  p.deactivation_time_constant_s = 0.05;
  p.activation_floor = 0.01;
}

std::string Thelen2003Muscle::slopeJumps() const {
  return "force-velocity slope doubles at u = 0, activation time constant switches at n = a, and passive "
         "force starts with a slope at the optimal fibre length";
}

void Thelen2003Muscle::validate(const MuscleParameters& p) const {
  require_positive(p, "force_length_width", p.force_length_width);
  require_positive(p, "hill_constant", p.hill_constant);
  if (!(p.max_eccentric_force_ratio > 1.0))
    reject(p, "max_eccentric_force_ratio", p.max_eccentric_force_ratio, "Flen must be > 1");
  require_positive(p, "passive_force_length_shape", p.passive_force_length_shape);
}

// ---------------------------------------------------------------- tendon
CurveJet Thelen2003Muscle::tendonForce(const MuscleParameters& p, double tendon_length_m) const {
  const double slack = p.tendon_slack_length_m, fmax = p.max_isometric_force_N;
  const double strain = (tendon_length_m - slack) / slack;  // not L / slack - 1: that loses the stretch's digits
  if (!(strain > 0.0)) return {};
  const Tendon t = tendon_constants(p);
  if (strain > t.toe_strain) {
    return {fmax * (t.linear_stiffness * (strain - t.toe_strain) + kToeForce), fmax * t.linear_stiffness / slack, 0.0};
  }
  const double rate = kToeShape / (t.toe_strain * slack);  // d(exponent)/dL_S
  const double e = std::exp(kToeShape * strain / t.toe_strain);
  const double scale = fmax * t.toe_scale;
  return {scale * (e - 1.0), scale * rate * e, scale * rate * rate * e};
}

double Thelen2003Muscle::tendonForceThirdDerivative(const MuscleParameters& p, double tendon_length_m) const {
  const double slack = p.tendon_slack_length_m;
  const double strain = (tendon_length_m - slack) / slack;  // not L / slack - 1: that loses the stretch's digits
  const Tendon t = tendon_constants(p);
  if (!(strain > 0.0) || strain > t.toe_strain) return 0.0;
  const double rate = kToeShape / (t.toe_strain * slack);
  return p.max_isometric_force_N * t.toe_scale * rate * rate * rate * std::exp(kToeShape * strain / t.toe_strain);
}

double Thelen2003Muscle::tendonLengthFromForce(const MuscleParameters& p, double tendon_force_N) const {
  if (!std::isfinite(tendon_force_N) || tendon_force_N <= 0.0)
    detail::domain_failure(p, "tendon length is defined only for a finite tendon force > 0 N", tendon_force_N);
  const Tendon t = tendon_constants(p);
  const double normalized = tendon_force_N / p.max_isometric_force_N;
  const double strain = normalized > kToeForce
                            ? t.toe_strain + (normalized - kToeForce) / t.linear_stiffness
                            : t.toe_strain / kToeShape * std::log1p(normalized / t.toe_scale);
  return p.tendon_slack_length_m * (1.0 + strain);
}

// ---------------------------------------------------------------- fibre
CurveJet Thelen2003Muscle::activeForceLength(const MuscleParameters& p, double fiber_length_m) const {
  // exp(-(l - 1)^2 / KshapeActive) with KshapeActive = W^2: a Gaussian of width W Lopt.
  return detail::gaussian_force_length(p, fiber_length_m);
}

CurveJet Thelen2003Muscle::passiveFiberForce(const MuscleParameters& p, double fiber_length_m) const {
  const double e0 = p.passive_fiber_strain_at_one_norm_force;
  if (!(e0 > 0.0)) return {};
  const double rate = p.passive_force_length_shape / (e0 * p.optimal_fiber_length_m);  // d(exponent)/dL_M
  const double y = (fiber_length_m - p.optimal_fiber_length_m) * rate;
  if (!(y > 0.0)) return {};
  const double scale = p.max_isometric_force_N / std::expm1(p.passive_force_length_shape);
  const double e = std::exp(y);
  return {scale * std::expm1(y), scale * rate * e, scale * rate * rate * e};
}

// OpenSim's Thelen muscle defines its force-velocity relation by the velocity it computes from the
// force ratio (fiberVelocityFromForceRatio): Thelen's two branches, continued linearly below z = 0
// and above z_lin = 0.95 Flen. g is the inverse of all of it, so the forward model is g's exact
// inverse at every force ratio, as in OpenSim.
CurveJet Thelen2003Muscle::forceVelocity(const MuscleParameters& p, double u) const {
  const double vmax = p.max_shortening_velocity_m_per_s();
  const double af = p.hill_constant, flen = p.max_eccentric_force_ratio;
  if (u > vmax) return {(u - vmax) / (vmax * velocity_exact_slope(p, 0.0)), 1.0 / (vmax * velocity_exact_slope(p, 0.0)), 0.0};
  if (u >= 0.0) {  // z = Af (Vmax - u) / (Af Vmax + u), the inverse of the concentric branch
    const double den = af * vmax + u;
    return {af * (vmax - u) / den, -af * vmax * (1.0 + af) / (den * den),
            2.0 * af * vmax * (1.0 + af) / (den * den * den)};
  }
  const double z_lin = kLinearExtrapolationThreshold * flen;
  const double u_lin = vmax * velocity_exact(p, z_lin), slope_lin = vmax * velocity_exact_slope(p, z_lin);
  if (u < u_lin) return {z_lin + (u - u_lin) / slope_lin, 1.0 / slope_lin, 0.0};
  // Eccentric: with w = -u / Vmax and k = (2 + 2 / Af) / (Flen - 1), z = (1 + k w Flen) / (1 + k w).
  const double k = (2.0 + 2.0 / af) / (flen - 1.0);
  const double w = -u / vmax;
  const double den = 1.0 + k * w;
  return {(1.0 + k * w * flen) / den, -k * (flen - 1.0) / (vmax * den * den),
          -2.0 * k * k * (flen - 1.0) / (vmax * vmax * den * den * den)};
}

double Thelen2003Muscle::forceVelocityInverse(const MuscleParameters& p, double z) const {
  if (!std::isfinite(z)) detail::domain_failure(p, "force-velocity inverse needs a finite force ratio", z);
  return fiberVelocityFromForceRatio(p, z).value;
}

double Thelen2003Muscle::forceRatioExactUpperBound(const MuscleParameters&) const {
  return std::numeric_limits<double>::infinity();
}

CurveJet Thelen2003Muscle::fiberVelocityFromForceRatio(const MuscleParameters& p, double z) const {
  const double vmax = p.max_shortening_velocity_m_per_s();
  const double z_lin = kLinearExtrapolationThreshold * p.max_eccentric_force_ratio;
  const double at = std::clamp(z, 0.0, z_lin);
  const double slope = vmax * velocity_exact_slope(p, at);
  return {vmax * velocity_exact(p, at) + slope * (z - at), slope, 0.0};
}

// ---------------------------------------------------------------- activation
ActivationRate Thelen2003Muscle::activationRate(const MuscleParameters& p, double excitation, double activation) const {
  return detail::first_order_activation_rate(p, excitation, activation);
}

ExcitationFromActivation Thelen2003Muscle::excitationFromActivation(const MuscleParameters& p, double activation,
                                                                    double rate) const {
  return detail::first_order_excitation_from_activation(p, activation, rate);
}

ExcitationBoundMargins Thelen2003Muscle::excitationBoundMargins(const MuscleParameters& p, double activation,
                                                                double rate) const {
  return detail::first_order_excitation_bound_margins(p, activation, rate);
}

}  // namespace flatsos::muscles
