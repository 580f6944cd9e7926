// OpenSim 2.x's Thelen2003Muscle (thelen2003_opensim2_muscle.hpp).

#include "flatsos/muscles/thelen2003_opensim2_muscle.hpp"

#include <algorithm>
#include <cmath>

#include "parameter_checks.hpp"
#include "shared_curves.hpp"

namespace flatsos::muscles {
namespace {

// OpenSim 2.x's tendon constants, as rounded there.
constexpr double kToeStrainPerE0 = 0.609;
constexpr double kOpenSim2ToeForce = 0.333333;
constexpr double kLinearStiffnessTimesE0 = 1.712;
constexpr double kOpenSim2ToeShape = 3.0;
constexpr double kSlackTendonForce = 0.001;  // times (1 + e), at every strain
// The velocity law's constants: the activation floor inside it, the force step of its
// extrapolation slopes, and where the eccentric branch is extrapolated.
constexpr double kVelocityActivationFloor = 1e-6;
constexpr double kSlopeStep = 1e-6;
constexpr double kExtrapolationThreshold = 0.95;

// Normalized tendon force fse(e) and its first three derivatives in e.
struct TendonJet {
  double value = 0.0, d1 = 0.0, d2 = 0.0, d3 = 0.0;
};
TendonJet tendon_jet(const MuscleParameters& p, double strain) {
  const double e0 = p.tendon_strain_at_max_force;
  const double toe_strain = kToeStrainPerE0 * e0, stiffness = kLinearStiffnessTimesE0 / e0;
  TendonJet t{kSlackTendonForce * (1.0 + strain), kSlackTendonForce, 0.0, 0.0};
  if (strain > toe_strain) {
    t.value += stiffness * (strain - toe_strain) + kOpenSim2ToeForce;
    t.d1 += stiffness;
  } else if (strain > 0.0) {
    const double rate = kOpenSim2ToeShape / toe_strain, scale = kOpenSim2ToeForce / std::expm1(kOpenSim2ToeShape);
    const double e = std::exp(rate * strain);
    t.value += scale * (e - 1.0);
    t.d1 += scale * rate * e;
    t.d2 = scale * rate * rate * e;
    t.d3 = scale * rate * rate * rate * e;
  }
  return t;
}

// Lengthening velocity per Vmax(a) from the fibre's force Fv and its active capacity Fa (both per
// Fmax), OpenSim 2.x's calcFiberVelocity, with its partial derivatives in Fv and Fa (each branch
// is rational in both; the extrapolations are straight lines through two of its points).
struct VelocityLaw {
  double value = 0.0, d_force = 0.0, d_capacity = 0.0;
};
VelocityLaw lengthening_velocity(double fv, double fa, double af, double flen, double damping) {
  const auto concentric = [&](double f) {
    const double den = fa + f / af + damping;
    return VelocityLaw{(f - fa) / den, (den - (f - fa) / af) / (den * den), (-den - (f - fa)) / (den * den)};
  };
  const double slope_b = (2.0 + 2.0 / af) / (flen - 1.0);  // b(f) = slope_b (fa flen - f)
  const auto eccentric = [&](double f) {
    const double den = slope_b * (fa * flen - f) + damping;
    return VelocityLaw{(f - fa) / den, (den + slope_b * (f - fa)) / (den * den),
                       (-den - (f - fa) * slope_b * flen) / (den * den)};
  };
  if (fv < fa) {
    if (fv >= 0.0) return concentric(fv);
    const VelocityLaw c0 = concentric(0.0), c1 = concentric(kSlopeStep);
    const double slope = (c1.value - c0.value) / kSlopeStep;
    return {c0.value + fv * slope, slope, c0.d_capacity + fv * (c1.d_capacity - c0.d_capacity) / kSlopeStep};
  }
  const double f0_per_fa = kExtrapolationThreshold * flen, f1_per_fa = (kExtrapolationThreshold + kSlopeStep) * flen;
  const double f0 = f0_per_fa * fa;
  if (fv < f0) return eccentric(fv);
  // Through e(f0) and e(f1), f0 and f1 proportional to fa.
  const double f1 = f1_per_fa * fa;
  const VelocityLaw e0 = eccentric(f0), e1 = eccentric(f1);
  const double slope = (e1.value - e0.value) / (f1 - f0);
  const double de0 = e0.d_force * f0_per_fa + e0.d_capacity, de1 = e1.d_force * f1_per_fa + e1.d_capacity;
  const double d_slope = ((de1 - de0) * (f1 - f0) - (e1.value - e0.value) * (f1_per_fa - f0_per_fa)) / ((f1 - f0) * (f1 - f0));
  return {e0.value + slope * (fv - f0), slope, de0 + d_slope * (fv - f0) - slope * f0_per_fa};
}

}  // namespace

void Thelen2003OpenSim2Muscle::setDefaults(MuscleParameters& p) const {
  p.tendon_strain_at_max_force = 0.033;
  p.force_length_width = std::sqrt(0.5);
  p.passive_fiber_strain_at_one_norm_force = 0.6;
  p.passive_force_length_shape = 4.0;
  p.hill_constant = 0.3;
  p.max_eccentric_force_ratio = 1.8;
  p.max_shortening_velocity_in_optimal_lengths_per_s = 10.0;
  p.activation_time_constant_s = 0.01;
  p.deactivation_time_constant_s = 0.04;
  p.activation_floor = kVelocityActivationFloor;
  p.fiber_damping = 0.05;
}

std::string Thelen2003OpenSim2Muscle::slopeJumps() const {
  return "tendon force slope jumps at the toe's end, activation time constant switches at n = a, and the velocity "
         "law's slope at Fv = 0 and 0.95 Fa Flen";
}

void Thelen2003OpenSim2Muscle::validate(const MuscleParameters& p) const {
  undamped_.validate(p);
  require_positive(p, "passive_fiber_strain_at_one_norm_force", p.passive_fiber_strain_at_one_norm_force);
  if (!(p.max_shortening_velocity_in_optimal_lengths_per_s > kMaxVelocityAtRestInOptimalLengthsPerS))
    reject(p, "max_shortening_velocity_in_optimal_lengths_per_s", p.max_shortening_velocity_in_optimal_lengths_per_s,
           "must exceed OpenSim 2.x's Vmax0 = 5 optimal lengths per second");
}

// ---------------------------------------------------------------- tendon
CurveJet Thelen2003OpenSim2Muscle::tendonForce(const MuscleParameters& p, double tendon_length_m) const {
  const double slack = p.tendon_slack_length_m, fmax = p.max_isometric_force_N;
  const TendonJet t = tendon_jet(p, (tendon_length_m - slack) / slack);
  return {fmax * t.value, fmax * t.d1 / slack, fmax * t.d2 / (slack * slack)};
}

double Thelen2003OpenSim2Muscle::tendonForceThirdDerivative(const MuscleParameters& p, double tendon_length_m) const {
  const double slack = p.tendon_slack_length_m;
  return p.max_isometric_force_N * tendon_jet(p, (tendon_length_m - slack) / slack).d3 / (slack * slack * slack);
}

double Thelen2003OpenSim2Muscle::tendonLengthFromForce(const MuscleParameters& p, double tendon_force_N) const {
  if (!std::isfinite(tendon_force_N) || tendon_force_N <= 0.0)
    detail::domain_failure(p, "tendon length is defined only for a finite tendon force > 0 N", tendon_force_N);
  const double n = tendon_force_N / p.max_isometric_force_N;
  const double e0 = p.tendon_strain_at_max_force, toe_strain = kToeStrainPerE0 * e0;
  const double stiffness = kLinearStiffnessTimesE0 / e0;
  double strain = 0.0;
  if (n <= kSlackTendonForce) {
    strain = n / kSlackTendonForce - 1.0;
  } else if (n >= tendon_jet(p, toe_strain).value) {
    strain = (n - kOpenSim2ToeForce - kSlackTendonForce + stiffness * toe_strain) / (stiffness + kSlackTendonForce);
  } else {  // the toe: increasing and convex, so Newton from its end converges from above
    strain = toe_strain;
    for (int i = 0; i < 100; ++i) {
      const TendonJet t = tendon_jet(p, strain);
      const double step = (t.value - n) / t.d1;
      strain = std::max(strain - step, 0.0);
      if (std::abs(step) <= 1e-15 * (1.0 + strain)) break;
    }
  }
  return p.tendon_slack_length_m * (1.0 + strain);
}

// ---------------------------------------------------------------- fibre
CurveJet Thelen2003OpenSim2Muscle::activeForceLength(const MuscleParameters& p, double fiber_length_m) const {
  return detail::gaussian_force_length(p, fiber_length_m);
}

CurveJet Thelen2003OpenSim2Muscle::passiveFiberForce(const MuscleParameters& p, double fiber_length_m) const {
  const double e0 = p.passive_fiber_strain_at_one_norm_force, shape = p.passive_force_length_shape;
  const double lopt = p.optimal_fiber_length_m, fmax = p.max_isometric_force_N;
  const double stretch = fiber_length_m / lopt - 1.0;
  const double rate = shape / e0;  // per unit l
  if (stretch > e0) return {fmax * (1.0 + rate * (stretch - e0)), fmax * rate / lopt, 0.0};
  const double value = std::exp(rate * stretch - shape);
  return {fmax * value, fmax * rate * value / lopt, fmax * rate * rate * value / (lopt * lopt)};
}

CurveJet Thelen2003OpenSim2Muscle::maxVelocityScale(const MuscleParameters& p, double activation) const {
  const double vmax = p.max_shortening_velocity_in_optimal_lengths_per_s, v0 = kMaxVelocityAtRestInOptimalLengthsPerS;
  return {(v0 + activation * (vmax - v0)) / vmax, (vmax - v0) / vmax, 0.0};
}

OwnFiberVelocity Thelen2003OpenSim2Muscle::ownFiberVelocity(const MuscleParameters& p, double activation,
                                                              double fiber_length_m, double fiber_force_N) const {
  // u = -Vmax(a) Lopt V(A / Fmax, max(a, floor) f(L_M)), exact partials (the muscle's inverse
  // differentiates them once more).
  const double fmax = p.max_isometric_force_N, lopt = p.optimal_fiber_length_m;
  const double vmax = p.max_shortening_velocity_in_optimal_lengths_per_s, v0 = kMaxVelocityAtRestInOptimalLengthsPerS;
  const bool above_floor = activation > kVelocityActivationFloor;
  const double a_law = above_floor ? activation : kVelocityActivationFloor;
  const CurveJet f = activeForceLength(p, fiber_length_m);
  const VelocityLaw v = lengthening_velocity(fiber_force_N / fmax, a_law * f.value, p.hill_constant,
                                             p.max_eccentric_force_ratio, p.fiber_damping);
  const double speed_m_per_s = (activation < 1.0 ? v0 + activation * (vmax - v0) : vmax) * lopt;
  const double speed_d_activation = activation < 1.0 ? (vmax - v0) * lopt : 0.0;
  OwnFiberVelocity out;
  out.shortening_m_per_s = -speed_m_per_s * v.value;
  out.d_fiber_force = -speed_m_per_s * v.d_force / fmax;
  out.d_fiber_length = -speed_m_per_s * v.d_capacity * a_law * f.slope;
  out.d_activation = -speed_d_activation * v.value - speed_m_per_s * v.d_capacity * (above_floor ? f.value : 0.0);
  return out;
}

// ---------------------------------------------------------------- activation
ActivationRate Thelen2003OpenSim2Muscle::activationRate(const MuscleParameters& p, double excitation,
                                                        double activation) const {
  const double T = excitation >= activation ? p.activation_time_constant_s : p.deactivation_time_constant_s;
  ActivationRate r;
  r.value = (excitation - activation) / T;
  r.d_excitation = 1.0 / T;
  r.d_activation = -1.0 / T;
  return r;
}

ExcitationFromActivation Thelen2003OpenSim2Muscle::excitationFromActivation(const MuscleParameters& p,
                                                                            double activation, double rate) const {
  const double T = rate >= 0.0 ? p.activation_time_constant_s : p.deactivation_time_constant_s;
  ExcitationFromActivation out;
  out.excitation = activation + rate * T;
  out.d_activation = 1.0;
  out.d_activation_rate_s = T;
  return out;
}

ExcitationBoundMargins Thelen2003OpenSim2Muscle::excitationBoundMargins(const MuscleParameters& p, double activation,
                                                                        double rate) const {
  // n = a + rate T_deact while deactivating (only there can n < 0), a + rate T_act while
  // activating (only there can n > 1); each margin is its branch's, smooth in (a, rate).
  const double Ta = p.activation_time_constant_s, Td = p.deactivation_time_constant_s;
  ExcitationBoundMargins m;
  m.lower = activation + rate * Td;
  m.lower_d_activation = 1.0;
  m.lower_d_rate_s = Td;
  m.upper = 1.0 - activation - rate * Ta;
  m.upper_d_activation = -1.0;
  m.upper_d_rate_s = -Ta;
  return m;
}

}  // namespace flatsos::muscles
