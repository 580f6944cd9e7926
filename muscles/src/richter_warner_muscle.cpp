#include "flatsos/muscles/richter_warner_muscle.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "parameter_checks.hpp"
#include "shared_curves.hpp"

namespace flatsos::muscles {
namespace {

// Fraction of (1, gmax) on which the forward model uses the exact eccentric inverse.
constexpr double kExactEccentricFraction = 0.9;

double tendon_stiffness_N_per_m2(const MuscleParameters& p) {
  const double stretch_at_fmax = p.tendon_strain_at_max_force * p.tendon_slack_length_m;
  return p.max_isometric_force_N / (stretch_at_fmax * stretch_at_fmax);
}

// Coefficient c of the eccentric inverse u = -c (z - 1) / (gmax - z).
double eccentric_inverse_coefficient(const MuscleParameters& p) {
  const double ah = p.hill_constant;
  return (p.max_eccentric_force_ratio - 1.0) * ah * p.max_shortening_velocity_m_per_s() / (ah + 1.0);
}

// Exact inverse of g and its derivative without range checks (callers check).
double inverse_unchecked(const MuscleParameters& p, double z) {
  const double vmax = p.max_shortening_velocity_m_per_s();
  if (z <= 1.0) return vmax * (1.0 - z) / (1.0 + z / p.hill_constant);
  return -eccentric_inverse_coefficient(p) * (z - 1.0) / (p.max_eccentric_force_ratio - z);
}
double inverse_derivative_unchecked(const MuscleParameters& p, double z) {
  const double vmax = p.max_shortening_velocity_m_per_s();
  const double ah = p.hill_constant;
  if (z <= 1.0) {
    const double den = 1.0 + z / ah;
    return -vmax * (1.0 + 1.0 / ah) / (den * den);
  }
  const double gap = p.max_eccentric_force_ratio - z;
  return -eccentric_inverse_coefficient(p) * (p.max_eccentric_force_ratio - 1.0) / (gap * gap);
}

// exp(y) - sum_{n < first} y^n / n!, by its series for small y (no cancellation; terms to
// y^(first + 10), below round-off for |y| < 0.1) and by expm1 above.
double exp_tail(double y, int first) {
  if (std::abs(y) < 0.1) {
    double term = 1.0;
    for (int n = 1; n <= first; ++n) term *= y / n;
    double sum = 0.0;
    for (int n = first; n <= first + 10; ++n) {
      sum += term;
      term *= y / (n + 1);
    }
    return sum;
  }
  double sum = std::expm1(y), term = y;
  for (int n = 1; n < first; ++n) {
    sum -= term;
    term *= y / (n + 1);
  }
  return sum;
}

}  // namespace

void RichterWarnerMuscle::validate(const MuscleParameters& p) const {
  require_positive(p, "force_length_width", p.force_length_width);
  require_positive(p, "hill_constant", p.hill_constant);
  require_positive(p, "max_eccentric_force_ratio", p.max_eccentric_force_ratio);
  require_positive(p, "passive_force_length_shape", p.passive_force_length_shape);
  if (p.max_eccentric_force_ratio <= 1.0)
    reject(p, "max_eccentric_force_ratio", p.max_eccentric_force_ratio,
           "must be > 1: eccentric force exceeds isometric force");
  if (p.activation_time_constant_s > p.deactivation_time_constant_s)
    reject(p, "activation_time_constant_s", p.activation_time_constant_s,
           "must not exceed deactivation_time_constant_s: activation is faster than deactivation");
}

void RichterWarnerMuscle::setDefaults(MuscleParameters& p) const {
  const MuscleParameters defaults;
  p.tendon_strain_at_max_force = defaults.tendon_strain_at_max_force;
  p.force_length_width = defaults.force_length_width;
  p.max_shortening_velocity_in_optimal_lengths_per_s = defaults.max_shortening_velocity_in_optimal_lengths_per_s;
  p.hill_constant = defaults.hill_constant;
  p.max_eccentric_force_ratio = defaults.max_eccentric_force_ratio;
  p.activation_time_constant_s = defaults.activation_time_constant_s;
  p.deactivation_time_constant_s = defaults.deactivation_time_constant_s;
  p.activation_floor = defaults.activation_floor;
  p.passive_fiber_strain_at_one_norm_force = defaults.passive_fiber_strain_at_one_norm_force;
  p.passive_force_length_shape = defaults.passive_force_length_shape;
}

// ---------------------------------------------------------------- tendon
CurveJet RichterWarnerMuscle::tendonForce(const MuscleParameters& p, double tendon_length_m) const {
  const double stretch = tendon_length_m - p.tendon_slack_length_m;
  if (!(stretch > 0.0)) return {};
  const double k = tendon_stiffness_N_per_m2(p);
  return {k * stretch * stretch, 2.0 * k * stretch, 2.0 * k};
}

double RichterWarnerMuscle::tendonLengthFromForce(const MuscleParameters& p, double tendon_force_N) const {
  if (!std::isfinite(tendon_force_N) || tendon_force_N <= 0.0)
    detail::domain_failure(p, "tendon length is defined only for a finite tendon force > 0 N", tendon_force_N);
  return p.tendon_slack_length_m + std::sqrt(tendon_force_N / tendon_stiffness_N_per_m2(p));
}

// ---------------------------------------------------------------- fibre
CurveJet RichterWarnerMuscle::activeForceLength(const MuscleParameters& p, double fiber_length_m) const {
  return detail::gaussian_force_length(p, fiber_length_m);
}

CurveJet RichterWarnerMuscle::passiveFiberForce(const MuscleParameters& p, double fiber_length_m) const {
  const double e0 = p.passive_fiber_strain_at_one_norm_force;
  if (!(e0 > 0.0)) return {};
  const double dy_dlength = p.passive_force_length_shape / (e0 * p.optimal_fiber_length_m);
  const double y = (fiber_length_m - p.optimal_fiber_length_m) * dy_dlength;
  if (!(y > 0.0)) return {};
  const double scale = p.max_isometric_force_N / exp_tail(p.passive_force_length_shape, 3);
  return {scale * exp_tail(y, 3), scale * exp_tail(y, 2) * dy_dlength,
          scale * std::expm1(y) * dy_dlength * dy_dlength};
}

CurveJet RichterWarnerMuscle::forceVelocity(const MuscleParameters& p, double u) const {
  const double vmax = p.max_shortening_velocity_m_per_s();
  const double ah = p.hill_constant;
  const double gmax = p.max_eccentric_force_ratio;
  if (u >= 0.0) {
    const double den = ah * vmax + u;
    return {ah * (vmax - u) / den, -ah * vmax * (1.0 + ah) / (den * den),
            2.0 * ah * vmax * (1.0 + ah) / (den * den * den)};
  }
  const double c0 = ah * vmax * (1.0 - gmax);  // < 0
  const double den = c0 + u * (1.0 + ah);
  return {(c0 + u * gmax * (1.0 + ah)) / den, c0 * (1.0 + ah) * (gmax - 1.0) / (den * den),
          -2.0 * c0 * (1.0 + ah) * (1.0 + ah) * (gmax - 1.0) / (den * den * den)};
}

double RichterWarnerMuscle::forceVelocityInverse(const MuscleParameters& p, double z) const {
  if (!(z > -p.hill_constant && z < p.max_eccentric_force_ratio))
    detail::domain_failure(p, "force-velocity inverse needs a force ratio in (-Ah, gmax)", z);
  return inverse_unchecked(p, z);
}

double RichterWarnerMuscle::forceRatioExactUpperBound(const MuscleParameters& p) const {
  return 1.0 + kExactEccentricFraction * (p.max_eccentric_force_ratio - 1.0);
}

CurveJet RichterWarnerMuscle::fiberVelocityFromForceRatio(const MuscleParameters& p, double z) const {
  // Continued linearly below 0 (the fibre pushes: only with a passive element or round-off) and
  // above z_hi (the pole at gmax would send u to -inf): C1 and strictly decreasing.
  if (z < 0.0) {
    const double slope = inverse_derivative_unchecked(p, 0.0);
    return {inverse_unchecked(p, 0.0) + slope * z, slope, 0.0};
  }
  const double z_hi = forceRatioExactUpperBound(p);
  if (z > z_hi) {
    const double slope = inverse_derivative_unchecked(p, z_hi);
    return {inverse_unchecked(p, z_hi) + slope * (z - z_hi), slope, 0.0};
  }
  return {inverse_unchecked(p, z), inverse_derivative_unchecked(p, z), 0.0};
}

// ---------------------------------------------------------------- activation
ActivationRate RichterWarnerMuscle::activationRate(const MuscleParameters& p, double n, double a) const {
  const double beta = p.activation_beta(), T = p.activation_time_constant_s;
  const double sigma = (beta + (1.0 - beta) * n) / T;
  ActivationRate r;
  r.value = sigma * (n - a);
  r.d_excitation = ((1.0 - beta) * (2.0 * n - a) + beta) / T;
  r.d_activation = -sigma;
  r.d_excitation2 = 2.0 * (1.0 - beta) / T;
  r.d_excitation_activation = -(1.0 - beta) / T;
  return r;
}

ExcitationFromActivation RichterWarnerMuscle::excitationFromActivation(const MuscleParameters& p, double a,
                                                                      double adot) const {
  // Q(n) = (1 - beta) n^2 + (beta - (1 - beta) a) n - beta a - T_act da/dt = 0, larger root.
  const double beta = p.activation_beta();
  const double qa = 1.0 - beta;
  const double qb = beta - (1.0 - beta) * a;
  const double qc = -beta * a - p.activation_time_constant_s * adot;
  const double disc = qb * qb - 4.0 * qa * qc;
  ExcitationFromActivation out;
  if (disc < 0.0) {
    out.real_root = false;
    out.excitation = -qb / (2.0 * qa);
    return out;
  }
  // Cancellation-free quadratic roots; keep the larger one.
  const double sq = std::sqrt(disc);
  const double q = -0.5 * (qb + (qb >= 0.0 ? sq : -sq));
  const double r1 = q / qa;
  const double r2 = q != 0.0 ? qc / q : r1;
  const double n = std::max(r1, r2);
  out.excitation = n;
  // Implicit function theorem on Q(n, a, da/dt) = 0.
  const double Q_n = 2.0 * qa * n + qb;
  out.d_activation = ((1.0 - beta) * n + beta) / Q_n;
  out.d_activation_rate_s = p.activation_time_constant_s / Q_n;
  return out;
}

ExcitationBoundMargins RichterWarnerMuscle::excitationBoundMargins(const MuscleParameters& p, double a,
                                                                  double adot) const {
  const double T = p.activation_time_constant_s, beta = p.activation_beta();
  ExcitationBoundMargins m;
  // -T_act times the fastest deactivation rate any n in [0, 1] gives, and its slope in a.
  double fastest = beta * a, fastest_d_a = beta;
  if (a > beta / (1.0 - beta)) {
    const double s = beta + (1.0 - beta) * a;
    fastest = s * s / (4.0 * (1.0 - beta));
    fastest_d_a = 0.5 * s;
  }
  m.lower = T * adot + fastest;
  m.lower_d_activation = fastest_d_a;
  m.lower_d_rate_s = T;
  m.upper = 1.0 - a - T * adot;
  m.upper_d_activation = -1.0;
  m.upper_d_rate_s = -T;
  return m;
}

}  // namespace flatsos::muscles
