#include "flatsos/muscles/degroote_fregly2016_muscle.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "parameter_checks.hpp"
#include "shared_curves.hpp"

namespace flatsos::muscles {
namespace {

// The curves' constants, as OpenSim's DeGrooteFregly2016Muscle fixes them (De Groote et al. 2016,
// with OpenSim's corrections: b11 such that f(1) = 1; c2 = 1, c3 = 0.2 so the tendon carries no
// force at slack; d1 and d4 such that g passes through (-1, 0) and (0, 1)).
struct GaussianLike {
  double b1, b2, b3, b4;
};
constexpr std::array<GaussianLike, 3> kActiveForceLength{{
    {0.8150671134243542, 1.055033428970575, 0.162384573599574, 0.063303448465465},
    {0.433004984392647, 0.716775413397760, -0.029947116970696, 0.200356847296188},
    {0.1, 1.0, 0.353553390593274, 0.0},
}};
constexpr double kTendonC1 = 0.2, kTendonC3 = 0.2;  // c2 = 1: the exponent is kT times the strain
constexpr double kVelocityD1 = -0.3211346127989808, kVelocityD2 = -8.149, kVelocityD3 = -0.374,
                 kVelocityD4 = 0.8825327733249912;
// The least normalized fibre length of the model: the passive curve is 0 there.
constexpr double kMinNormalizedFiberLength = 0.2;

// kT = ln((1 + c3) / c1) / e0: the tendon carries Fmax at the strain e0.
double tendon_stiffness(const MuscleParameters& p) {
  return std::log((1.0 + kTendonC3) / kTendonC1) / p.tendon_strain_at_max_force;
}

// One Gaussian-like term b1 exp(q), q = -(x - b2)^2 / (2 w^2), w = b3 + b4 x, with its first two
// derivatives in x. Where w passes through 0 (x = 0.149 for the second term, far below the
// model's least fibre length) the term and its derivatives vanish: exp(q) underflows first.
CurveJet gaussian_like(const GaussianLike& c, double x) {
  const double w = c.b3 + c.b4 * x;
  const double r = (x - c.b2) / w;
  const double q = -0.5 * r * r;
  if (!(q > -700.0)) return {};
  const double r_x = (c.b3 + c.b4 * c.b2) / (w * w);
  const double r_xx = -2.0 * c.b4 * r_x / w;
  const double q_x = -r * r_x, q_xx = -(r_x * r_x + r * r_xx);
  const double e = c.b1 * std::exp(q);
  return {e, e * q_x, e * (q_x * q_x + q_xx)};
}

// Normalized lengthening velocity v from g on its exact inverse, with dv/dg.
double lengthening_from_ratio(double z) { return (std::sinh((z - kVelocityD4) / kVelocityD1) - kVelocityD3) / kVelocityD2; }
double lengthening_from_ratio_slope(double z) {
  return std::cosh((z - kVelocityD4) / kVelocityD1) / (kVelocityD1 * kVelocityD2);
}

// rate(n, a) = K(d, a) d with d = n - a, K = (A + D) / 2 + (A - D) tanh(b d) / 2, A = 1 / (T_act s),
// D = s / T_deact, s = 1/2 + 3/2 a; partials of R(d, a) = K d, then by the chain rule in (n, a).
ActivationRate activation_rate(const MuscleParameters& p, double n, double a) {
  const double Ta = p.activation_time_constant_s, Td = p.deactivation_time_constant_s;
  const double b = p.activation_dynamics_smoothing;
  const double d = n - a, s = 0.5 + 1.5 * a;
  const double A = 1.0 / (Ta * s), D = s / Td;
  const double A_a = -1.5 / (Ta * s * s), A_aa = 4.5 / (Ta * s * s * s), D_a = 1.5 / Td;
  const double t = std::tanh(b * d), sech2 = 1.0 - t * t;
  const double K = 0.5 * (A + D) + 0.5 * (A - D) * t;
  const double K_d = 0.5 * (A - D) * b * sech2, K_dd = -(A - D) * b * b * t * sech2;
  const double K_a = 0.5 * (A_a + D_a) + 0.5 * (A_a - D_a) * t;
  const double K_da = 0.5 * (A_a - D_a) * b * sech2, K_aa = 0.5 * A_aa * (1.0 + t);
  const double R_d = K + d * K_d, R_dd = 2.0 * K_d + d * K_dd;
  const double R_a = d * K_a, R_da = K_a + d * K_da, R_aa = d * K_aa;
  ActivationRate r;
  r.value = K * d;
  r.d_excitation = R_d;
  r.d_activation = R_a - R_d;
  r.d_excitation2 = R_dd;
  r.d_excitation_activation = R_da - R_dd;
  r.d_activation2 = R_dd - 2.0 * R_da + R_aa;
  return r;
}

}  // namespace

void DeGrooteFregly2016Muscle::setDefaults(MuscleParameters& p) const {
  p.tendon_strain_at_max_force = 0.049;
  p.force_length_width = 1.0;
  p.passive_fiber_strain_at_one_norm_force = 0.6;
  p.passive_force_length_shape = 4.0;
  p.max_shortening_velocity_in_optimal_lengths_per_s = 10.0;
  p.activation_time_constant_s = 0.015;
  p.deactivation_time_constant_s = 0.060;
  p.activation_dynamics_smoothing = 0.1;
}

void DeGrooteFregly2016Muscle::validate(const MuscleParameters& p) const {
  if (!(p.force_length_width >= 1.0))
    reject(p, "force_length_width", p.force_length_width, "the active curve's width scale must be >= 1");
  require_positive(p, "tendon_strain_at_max_force", p.tendon_strain_at_max_force);
  require_positive(p, "passive_force_length_shape", p.passive_force_length_shape);
  require_positive(p, "activation_dynamics_smoothing", p.activation_dynamics_smoothing);
}

// ---------------------------------------------------------------- tendon
CurveJet DeGrooteFregly2016Muscle::tendonForce(const MuscleParameters& p, double tendon_length_m) const {
  const double slack = p.tendon_slack_length_m;
  const double strain = (tendon_length_m - slack) / slack;
  const double rate = tendon_stiffness(p) / slack;  // d(exponent)/dL_S
  const double scale = kTendonC1 * p.max_isometric_force_N;
  const double e = std::exp(rate * (tendon_length_m - slack));
  // c1 exp(kT e) - c3 with c1 = c3, written with expm1 so small stretches keep their digits.
  return {scale * std::expm1(tendon_stiffness(p) * strain), scale * rate * e, scale * rate * rate * e};
}

double DeGrooteFregly2016Muscle::tendonForceThirdDerivative(const MuscleParameters& p, double tendon_length_m) const {
  const double rate = tendon_stiffness(p) / p.tendon_slack_length_m;
  return kTendonC1 * p.max_isometric_force_N * rate * rate * rate *
         std::exp(rate * (tendon_length_m - p.tendon_slack_length_m));
}

double DeGrooteFregly2016Muscle::tendonLengthFromForce(const MuscleParameters& p, double tendon_force_N) const {
  if (!std::isfinite(tendon_force_N) || tendon_force_N <= 0.0)
    detail::domain_failure(p, "tendon length is defined only for a finite tendon force > 0 N", tendon_force_N);
  const double strain = std::log1p(tendon_force_N / (kTendonC1 * p.max_isometric_force_N)) / tendon_stiffness(p);
  return p.tendon_slack_length_m * (1.0 + strain);
}

// ---------------------------------------------------------------- fibre
CurveJet DeGrooteFregly2016Muscle::activeForceLength(const MuscleParameters& p, double fiber_length_m) const {
  const double scale = p.force_length_width;
  const double dx_dlength = 1.0 / (scale * p.optimal_fiber_length_m);
  const double x = (fiber_length_m / p.optimal_fiber_length_m - 1.0) / scale + 1.0;
  CurveJet f;
  for (const GaussianLike& c : kActiveForceLength) {
    const CurveJet term = gaussian_like(c, x);
    f.value += term.value;
    f.slope += term.slope * dx_dlength;
    f.curvature += term.curvature * dx_dlength * dx_dlength;
  }
  return f;
}

CurveJet DeGrooteFregly2016Muscle::passiveFiberForce(const MuscleParameters& p, double fiber_length_m) const {
  const double e0 = p.passive_fiber_strain_at_one_norm_force;
  if (!(e0 > 0.0)) return {};
  const double k = p.passive_force_length_shape;
  const double offset = std::exp(k * (kMinNormalizedFiberLength - 1.0) / e0);
  const double scale = p.max_isometric_force_N / (std::exp(k) - offset);
  const double rate = k / (e0 * p.optimal_fiber_length_m);  // d(exponent)/dL_M
  const double e = std::exp(rate * (fiber_length_m - p.optimal_fiber_length_m));
  return {scale * (e - offset), scale * rate * e, scale * rate * rate * e};
}

CurveJet DeGrooteFregly2016Muscle::forceVelocity(const MuscleParameters& p, double u) const {
  const double vmax = p.max_shortening_velocity_m_per_s();
  const double s = kVelocityD2 * (-u / vmax) + kVelocityD3;
  const double root = std::sqrt(1.0 + s * s);
  const double dg_ds = kVelocityD1 / root, d2g_ds2 = -kVelocityD1 * s / (root * root * root);
  const double ds_du = -kVelocityD2 / vmax;
  return {kVelocityD1 * std::asinh(s) + kVelocityD4, dg_ds * ds_du, d2g_ds2 * ds_du * ds_du};
}

double DeGrooteFregly2016Muscle::forceVelocityInverse(const MuscleParameters& p, double z) const {
  const double u = -p.max_shortening_velocity_m_per_s() * lengthening_from_ratio(z);
  if (!std::isfinite(u)) detail::domain_failure(p, "force-velocity inverse overflows for this force ratio", z);
  return u;
}

double DeGrooteFregly2016Muscle::forceRatioExactUpperBound(const MuscleParameters&) const {
  return kVelocityD1 * std::asinh(kVelocityD2 + kVelocityD3) + kVelocityD4;
}

CurveJet DeGrooteFregly2016Muscle::fiberVelocityFromForceRatio(const MuscleParameters& p, double z) const {
  const double vmax = p.max_shortening_velocity_m_per_s();
  const double at = std::clamp(z, 0.0, forceRatioExactUpperBound(p));
  const double slope = -vmax * lengthening_from_ratio_slope(at);
  return {-vmax * lengthening_from_ratio(at) + slope * (z - at), slope, 0.0};
}

// ---------------------------------------------------------------- activation
ActivationRate DeGrooteFregly2016Muscle::activationRate(const MuscleParameters& p, double excitation,
                                                        double activation) const {
  return activation_rate(p, excitation, activation);
}

ExcitationFromActivation DeGrooteFregly2016Muscle::excitationFromActivation(const MuscleParameters& p,
                                                                            double activation, double rate) const {
  const double a = activation;
  auto residual = [&](double n) { return activation_rate(p, n, a).value - rate; };
  // Start from the mean time constant's answer, bracket the root, then Newton steps kept inside
  // the bracket (bisection where a step leaves it).
  const ActivationRate at_a = activation_rate(p, a, a);
  double n = a + rate / at_a.d_excitation;
  double lo = n - 0.5, hi = n + 0.5;
  for (int k = 0; k < 60 && residual(lo) > 0.0; ++k) lo -= (hi - lo);
  for (int k = 0; k < 60 && residual(hi) < 0.0; ++k) hi += (hi - lo);
  for (int k = 0; k < 100; ++k) {
    const ActivationRate r = activation_rate(p, n, a);
    const double f = r.value - rate;
    if (f == 0.0) break;
    (f < 0.0 ? lo : hi) = n;
    double next = n - f / r.d_excitation;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double step = std::abs(next - n);
    n = next;
    if (step <= 4e-16 * (1.0 + std::abs(n))) break;
  }
  const ActivationRate r = activation_rate(p, n, a);
  ExcitationFromActivation out;
  out.excitation = n;
  out.d_activation_rate_s = 1.0 / r.d_excitation;
  out.d_activation = -r.d_activation / r.d_excitation;
  return out;
}

ExcitationBoundMargins DeGrooteFregly2016Muscle::excitationBoundMargins(const MuscleParameters& p, double activation,
                                                                        double rate) const {
  // rate(n, a) increases in n, so n >= 0 exactly when da/dt >= rate(0, a) and n <= 1 when
  // da/dt <= rate(1, a); the time constants scale both margins to excitation units.
  const ActivationRate at_zero = activation_rate(p, 0.0, activation);
  const ActivationRate at_one = activation_rate(p, 1.0, activation);
  const double Ta = p.activation_time_constant_s, Td = p.deactivation_time_constant_s;
  ExcitationBoundMargins m;
  m.lower = (rate - at_zero.value) * Td;
  m.lower_d_activation = -at_zero.d_activation * Td;
  m.lower_d_rate_s = Td;
  m.upper = (at_one.value - rate) * Ta;
  m.upper_d_activation = at_one.d_activation * Ta;
  m.upper_d_rate_s = -Ta;
  return m;
}

}  // namespace flatsos::muscles
