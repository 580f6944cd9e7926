#include "flatsos/muscles/hill_laws.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace flatsos::muscles {
namespace {

// Fraction of (1, gmax) on which the forward model uses the exact eccentric inverse.
constexpr double kExactEccentricFraction = 0.9;
// Floor on f(L_C) in the force ratio: only reached for fiber lengths many widths from Lopt.
constexpr double kForceLengthFloor = 1e-12;

[[noreturn]] void domain_failure(const MuscleParameters& p, const char* what, double value) {
  std::ostringstream msg;
  msg << "muscle '" << p.name << "': " << what << " (got " << value << ")";
  throw std::domain_error(msg.str());
}

// Coefficient c of the eccentric inverse u = -c (z - 1) / (gmax - z).
double eccentric_inverse_coefficient(const MuscleParameters& p) {
  const double ah = p.hill_constant;
  return (p.max_eccentric_force_ratio - 1.0) * ah * p.max_shortening_velocity_m_per_s() /
         (ah + 1.0);
}

// Exact inverse and its derivative without range checks (callers check).
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

}  // namespace

// ---------------------------------------------------------------- tendon
double tendon_force(const MuscleParameters& p, double tendon_length_m) {
  const double stretch = tendon_length_m - p.tendon_slack_length_m;
  return stretch > 0.0 ? p.tendon_stiffness_N_per_m2() * stretch * stretch : 0.0;
}

double tendon_force_derivative(const MuscleParameters& p, double tendon_length_m) {
  const double stretch = tendon_length_m - p.tendon_slack_length_m;
  return stretch > 0.0 ? 2.0 * p.tendon_stiffness_N_per_m2() * stretch : 0.0;
}

double tendon_force_second_derivative(const MuscleParameters& p, double tendon_length_m) {
  return tendon_length_m > p.tendon_slack_length_m ? 2.0 * p.tendon_stiffness_N_per_m2() : 0.0;
}

double tendon_length_from_force(const MuscleParameters& p, double tendon_force_N) {
  if (!std::isfinite(tendon_force_N) || tendon_force_N <= 0.0)
    domain_failure(p, "tendon length is defined only for a finite tendon force > 0 N",
                   tendon_force_N);
  return p.tendon_slack_length_m + std::sqrt(tendon_force_N / p.tendon_stiffness_N_per_m2());
}

// ---------------------------------------------------------------- force-length
double force_length(const MuscleParameters& p, double fiber_length_m) {
  const double x =
      (fiber_length_m - p.optimal_fiber_length_m) / (p.force_length_width * p.optimal_fiber_length_m);
  return std::exp(-x * x);
}

double force_length_derivative(const MuscleParameters& p, double fiber_length_m) {
  const double width = p.force_length_width * p.optimal_fiber_length_m;
  const double x = (fiber_length_m - p.optimal_fiber_length_m) / width;
  return -2.0 * x / width * std::exp(-x * x);
}

double force_length_second_derivative(const MuscleParameters& p, double fiber_length_m) {
  const double width = p.force_length_width * p.optimal_fiber_length_m;
  const double x = (fiber_length_m - p.optimal_fiber_length_m) / width;
  return (4.0 * x * x - 2.0) / (width * width) * std::exp(-x * x);
}

// ---------------------------------------------------------------- force-velocity
double force_velocity(const MuscleParameters& p, double u) {
  const double vmax = p.max_shortening_velocity_m_per_s();
  const double ah = p.hill_constant;
  const double gmax = p.max_eccentric_force_ratio;
  if (u >= 0.0) return ah * (vmax - u) / (ah * vmax + u);
  const double c0 = ah * vmax * (1.0 - gmax);  // < 0
  return (c0 + u * gmax * (1.0 + ah)) / (c0 + u * (1.0 + ah));
}

double force_velocity_derivative(const MuscleParameters& p, double u) {
  const double vmax = p.max_shortening_velocity_m_per_s();
  const double ah = p.hill_constant;
  const double gmax = p.max_eccentric_force_ratio;
  if (u >= 0.0) {
    const double den = ah * vmax + u;
    return -ah * vmax * (1.0 + ah) / (den * den);
  }
  const double c0 = ah * vmax * (1.0 - gmax);
  const double den = c0 + u * (1.0 + ah);
  return c0 * (1.0 + ah) * (gmax - 1.0) / (den * den);
}

double force_velocity_second_derivative(const MuscleParameters& p, double u) {
  const double vmax = p.max_shortening_velocity_m_per_s();
  const double ah = p.hill_constant;
  const double gmax = p.max_eccentric_force_ratio;
  if (u >= 0.0) {
    const double den = ah * vmax + u;
    return 2.0 * ah * vmax * (1.0 + ah) / (den * den * den);
  }
  const double c0 = ah * vmax * (1.0 - gmax);
  const double den = c0 + u * (1.0 + ah);
  return -2.0 * c0 * (1.0 + ah) * (1.0 + ah) * (gmax - 1.0) / (den * den * den);
}

double force_velocity_inverse(const MuscleParameters& p, double z) {
  if (!(z > -p.hill_constant && z < p.max_eccentric_force_ratio))
    domain_failure(p, "force-velocity inverse needs a force ratio in (-Ah, gmax)", z);
  return inverse_unchecked(p, z);
}

double force_ratio_exact_upper_bound(const MuscleParameters& p) {
  return 1.0 + kExactEccentricFraction * (p.max_eccentric_force_ratio - 1.0);
}

double fiber_velocity_from_force_ratio(const MuscleParameters& p, double z) {
  if (z < 0.0) return inverse_unchecked(p, 0.0) + inverse_derivative_unchecked(p, 0.0) * z;
  const double z_hi = force_ratio_exact_upper_bound(p);
  if (z > z_hi)
    return inverse_unchecked(p, z_hi) + inverse_derivative_unchecked(p, z_hi) * (z - z_hi);
  return inverse_unchecked(p, z);
}

double fiber_velocity_from_force_ratio_derivative(const MuscleParameters& p, double z) {
  if (z < 0.0) return inverse_derivative_unchecked(p, 0.0);
  const double z_hi = force_ratio_exact_upper_bound(p);
  return inverse_derivative_unchecked(p, std::min(z, z_hi));
}

// ---------------------------------------------------------------- passive fibre force
namespace {
// Shape constant of the passive curve (Thelen 2003's kPE).
constexpr double kPassiveShape = 4.0;
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
double exp_tail3(double y) { return exp_tail(y, 3); }
double exp_tail2(double y) { return exp_tail(y, 2); }
// Normalized passive force and its first two derivatives in y = kPE (L_M / Lopt - 1) / e0.
struct PassiveShape {
  double y = 0.0, scale = 0.0, dy_dlength = 0.0;
};
PassiveShape passive_shape(const MuscleParameters& p, double fiber_length_m) {
  PassiveShape s;
  const double e0 = p.passive_fiber_strain_at_one_norm_force;
  if (!(e0 > 0.0)) return s;
  s.dy_dlength = kPassiveShape / (e0 * p.optimal_fiber_length_m);
  s.y = (fiber_length_m - p.optimal_fiber_length_m) * s.dy_dlength;
  s.scale = p.max_isometric_force_N / exp_tail3(kPassiveShape);
  return s;
}
}  // namespace

double passive_fiber_force(const MuscleParameters& p, double fiber_length_m) {
  const PassiveShape s = passive_shape(p, fiber_length_m);
  return s.y > 0.0 ? s.scale * exp_tail3(s.y) : 0.0;
}

double passive_fiber_force_derivative(const MuscleParameters& p, double fiber_length_m) {
  const PassiveShape s = passive_shape(p, fiber_length_m);
  return s.y > 0.0 ? s.scale * exp_tail2(s.y) * s.dy_dlength : 0.0;
}

double passive_fiber_force_second_derivative(const MuscleParameters& p, double fiber_length_m) {
  const PassiveShape s = passive_shape(p, fiber_length_m);
  return s.y > 0.0 ? s.scale * std::expm1(s.y) * s.dy_dlength * s.dy_dlength : 0.0;
}

// ---------------------------------------------------------------- pennation
FiberGeometry fiber_geometry(const MuscleParameters& p, double along_tendon_m) {
  FiberGeometry g;
  const double h = p.fiber_thickness_m();
  if (h == 0.0) {  // fibres along the tendon: exactly the unpennated model
    g.length_m = along_tendon_m;
    g.cos_pennation = 1.0;
    g.length_d_along = 1.0;
    return g;
  }
  g.length_m = std::hypot(along_tendon_m, h);
  g.cos_pennation = along_tendon_m / g.length_m;
  g.length_d_along = g.cos_pennation;
  g.cos_pennation_d_along = h * h / (g.length_m * g.length_m * g.length_m);
  return g;
}

// ---------------------------------------------------------------- contraction dynamics
namespace {
// Smallest cos(pennation) the forward model divides by (pennation up to 89.4 degrees): a fibre
// squeezed to its thickness holds no tendon force, and this keeps the model finite there.
constexpr double kMinCosPennation = 1e-2;

// z = (F / cos - Phi_P(L_M)) / (max(a, floor) Fmax f(L_M)) and what its partials need.
struct ForceRatioParts {
  FiberGeometry geometry;
  double cos_pennation = 1.0;  // floored
  bool cos_floored = false;
  double f = 1.0;              // floored
  bool f_floored = false;
  double passive = 0.0;
  double denominator = 1.0;    // a_eff Fmax f
  double z = 0.0;
};
ForceRatioParts force_ratio_parts(const MuscleParameters& p, double tendon_force_N, double activation,
                                  double along_tendon_m) {
  ForceRatioParts r;
  r.geometry = fiber_geometry(p, along_tendon_m);
  r.cos_floored = r.geometry.cos_pennation < kMinCosPennation;
  r.cos_pennation = r.cos_floored ? kMinCosPennation : r.geometry.cos_pennation;
  const double f_raw = force_length(p, r.geometry.length_m);
  r.f_floored = !(f_raw >= kForceLengthFloor);
  r.f = r.f_floored ? kForceLengthFloor : f_raw;
  r.passive = p.hasPassiveFiberForce() ? passive_fiber_force(p, r.geometry.length_m) : 0.0;
  r.denominator = effective_activation(p, activation) * p.max_isometric_force_N * r.f;
  r.z = (tendon_force_N / r.cos_pennation - r.passive) / r.denominator;
  return r;
}
}  // namespace

double effective_activation(const MuscleParameters& p, double activation) {
  return std::max(activation, p.activation_floor);
}

double force_ratio(const MuscleParameters& p, double tendon_force_N, double activation, double along_tendon_m) {
  return force_ratio_parts(p, tendon_force_N, activation, along_tendon_m).z;
}

double fiber_shortening_velocity(const MuscleParameters& p, double tendon_force_N, double activation,
                                 double along_tendon_m) {
  return fiber_velocity_from_force_ratio(p, force_ratio(p, tendon_force_N, activation, along_tendon_m));
}

double tendon_length_derivative(const MuscleParameters& p, double tendon_length_m, double activation,
                                double musculotendon_length_m, double musculotendon_lengthening_rate_m_per_s) {
  const ForceRatioParts r =
      force_ratio_parts(p, tendon_force(p, tendon_length_m), activation, musculotendon_length_m - tendon_length_m);
  // The fibre shortens at u along itself, so the muscle along the tendon, x = L - L_S, shortens
  // at u / cos: dL_S/dt = dL/dt + u / cos.
  return fiber_velocity_from_force_ratio(p, r.z) / r.cos_pennation + musculotendon_lengthening_rate_m_per_s;
}

TendonLengthDerivativePartials tendon_length_derivative_partials(const MuscleParameters& p, double tendon_length_m,
                                                                 double activation, double musculotendon_length_m) {
  // dL_S/dt = w + dL/dt, w = g^-1(z) / cos(x), x = L - L_S, z as in force_ratio_parts.
  const double force = tendon_force(p, tendon_length_m);
  const ForceRatioParts r = force_ratio_parts(p, force, activation, musculotendon_length_m - tendon_length_m);
  const double c = r.cos_pennation;
  const double dc_dx = r.cos_floored ? 0.0 : r.geometry.cos_pennation_d_along;
  const double dlength_dx = r.geometry.length_d_along;
  const double df_dx = r.f_floored ? 0.0 : force_length_derivative(p, r.geometry.length_m) * dlength_dx;
  const double dpassive_dx =
      p.hasPassiveFiberForce() ? passive_fiber_force_derivative(p, r.geometry.length_m) * dlength_dx : 0.0;
  const double dz_dx = (-force * dc_dx / (c * c) - dpassive_dx) / r.denominator - r.z * df_dx / r.f;
  const double dz_dtendon_direct = tendon_force_derivative(p, tendon_length_m) / (c * r.denominator);
  const double a_eff = effective_activation(p, activation);
  const double dz_dactivation = activation > p.activation_floor ? -r.z / a_eff : 0.0;
  const double du_dz = fiber_velocity_from_force_ratio_derivative(p, r.z);
  double dw_dx = du_dz * dz_dx / c;
  if (dc_dx != 0.0) dw_dx -= fiber_velocity_from_force_ratio(p, r.z) * dc_dx / (c * c);
  // dx/dL_S = -1, dx/dL = 1.
  return {du_dz * dz_dtendon_direct / c - dw_dx, du_dz * dz_dactivation / c, dw_dx};
}

// ---------------------------------------------------------------- activation dynamics
double activation_rate_factor(const MuscleParameters& p, double n) {
  const double beta = p.activation_beta();
  return (beta + (1.0 - beta) * n) / p.activation_time_constant_s;
}

double activation_derivative(const MuscleParameters& p, double n, double a) {
  return activation_rate_factor(p, n) * (n - a);
}

double activation_derivative_d_excitation(const MuscleParameters& p, double n, double a) {
  const double beta = p.activation_beta();
  return ((1.0 - beta) * (n - a) + beta + (1.0 - beta) * n) / p.activation_time_constant_s;
}

double activation_derivative_d_activation(const MuscleParameters& p, double n, double /*a*/) {
  return -activation_rate_factor(p, n);
}

ExcitationFromActivation excitation_from_activation(const MuscleParameters& p, double a,
                                                    double adot) {
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
  out.excitation = std::max(r1, r2);
  return out;
}

ExcitationBoundMargins excitation_bound_margins(const MuscleParameters& p, double a, double adot) {
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
