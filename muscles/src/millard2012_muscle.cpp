// OpenSim's Millard2012EquilibriumMuscle behind the muscle-model seam (Millard et al. 2013,
// J Biomech Eng 135(2):021005; OpenSim 4's Millard2012EquilibriumMuscle,
// MuscleFixedWidthPennationModel and MuscleFirstOrderActivationDynamicModel). The curves are
// built in millard2012_curves.cpp; here they are scaled to SI units and, for the damped model,
// the force-velocity curve is inverted where OpenSim's forward model never needs its inverse.
#include "flatsos/muscles/millard2012_muscle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "first_order_activation.hpp"
#include "parameter_checks.hpp"
#include "shared_curves.hpp"

namespace flatsos::muscles {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
// OpenSim's MIN_NONZERO_DAMPING_COEFFICIENT: below it the muscle is the undamped model.
constexpr double kMinimumDamping = 0.001;
// The least activation floor OpenSim's undamped elastic model accepts.
constexpr double kUndampedMinimumActivation = 0.01;
// How closely a strain field must equal the curve's own (relative): the same number written
// twice, not a fit.
constexpr double kStrainAgreement = 1e-12;

bool is_damped(const Millard2012MuscleConfiguration& configuration) {
  return configuration.fiber_damping >= kMinimumDamping;
}

Millard2012CurveParameters parameters_in_use(const Millard2012CurveParameters& given,
                                             const Millard2012MuscleConfiguration& configuration) {
  if (!std::isfinite(configuration.fiber_damping))
    throw std::invalid_argument("Millard2012Muscle: fiber_damping must be finite");
  if (configuration.ignore_tendon_compliance)
    throw std::invalid_argument(
        "Millard2012Muscle: ignore_tendon_compliance = true is not supported (flatsos' muscles have an elastic tendon)");
  Millard2012CurveParameters in_use = millard2012_muscle_curve_parameters(given, configuration);
  in_use.fiber_force_length = resolved(in_use.fiber_force_length);
  in_use.tendon_force_length = resolved(in_use.tendon_force_length);
  in_use.fiber_compressive_force_length = resolved(in_use.fiber_compressive_force_length);
  in_use.fiber_compressive_force_cos_pennation = resolved(in_use.fiber_compressive_force_cos_pennation);
  return in_use;
}

double checked_maximum_pennation(double angle_rad) {
  if (!(angle_rad >= 0.0 && angle_rad <= 0.5 * 3.14159265358979323846))
    throw std::invalid_argument("Millard2012Muscle: maximum_pennation_angle must be in [0, pi/2] rad");
  return angle_rad;
}

/// The curve g follows (see the header): the damped muscle's own force-velocity curve, or the
/// one whose inverse OpenSim's undamped forward model evaluates.
QuinticBezierCurve velocity_curve(const Millard2012CurveParameters& in_use, bool damped) {
  if (damped) return force_velocity_curve(in_use.force_velocity);
  ForceVelocityCurveProperties inverted = in_use.force_velocity;
  inverted.concentric_slope_at_vmax = 0.5 * inverted.concentric_slope_near_vmax;
  inverted.eccentric_slope_at_vmax = 0.5 * inverted.eccentric_slope_near_vmax;
  return force_velocity_curve(inverted);
}

/// A normalised curve's jet in SI units: y scaled by value_scale, x = argument / argument_scale.
CurveJet scaled(const BezierCurveJet& j, double value_scale, double argument_scale) {
  return {value_scale * j.value, value_scale * j.first / argument_scale,
          value_scale * j.second / (argument_scale * argument_scale)};
}

void require_strain(const MuscleParameters& p, const char* field, double value, double curve_strain,
                    const char* curve) {
  if (std::abs(value - curve_strain) <= kStrainAgreement * curve_strain) return;
  std::ostringstream requirement;
  requirement << "must equal this Millard2012Muscle's " << curve << " strain_at_one_norm_force, " << curve_strain;
  reject(p, field, value, requirement.str().c_str());
}

}  // namespace

double Millard2012Muscle::flatEndContinuationSlope() { return std::sqrt(kEps); }

Millard2012Muscle::Millard2012Muscle() : Millard2012Muscle(Millard2012CurveParameters{}) {}

Millard2012Muscle::Millard2012Muscle(const Millard2012CurveParameters& curve_parameters,
                                     const Millard2012MuscleConfiguration& configuration,
                                     double maximum_pennation_angle_rad)
    : parameters_(parameters_in_use(curve_parameters, configuration)),
      damped_(is_damped(configuration)),
      damping_(damped_ ? configuration.fiber_damping : 0.0),
      maximum_pennation_angle_rad_(checked_maximum_pennation(maximum_pennation_angle_rad)),
      curves_(millard2012_curves(parameters_)),
      velocity_curve_(velocity_curve(parameters_, damped_)) {}

void Millard2012Muscle::setDefaults(MuscleParameters& p) const {
  p.max_shortening_velocity_in_optimal_lengths_per_s = 10.0;
  p.activation_time_constant_s = 0.010;
  p.deactivation_time_constant_s = 0.040;
  p.activation_floor = 0.01;
  p.fiber_damping = damping_;
  p.tendon_strain_at_max_force = parameters_.tendon_force_length.strain_at_one_norm_force;
  p.passive_fiber_strain_at_one_norm_force = parameters_.fiber_force_length.strain_at_one_norm_force;
}

void Millard2012Muscle::validate(const MuscleParameters& p) const {
  // The curves were adjusted for one formulation; a damping of the other kind would pair the
  // shared force balance with curves OpenSim never uses together.
  if (damped_ && p.fiber_damping < kMinimumDamping)
    reject(p, "fiber_damping", p.fiber_damping,
           "this Millard2012Muscle was built damped: its fiber_damping must be >= 0.001, as OpenSim's damped model");
  if (!damped_ && p.fiber_damping != 0.0)
    reject(p, "fiber_damping", p.fiber_damping,
           "this Millard2012Muscle was built undamped: its fiber_damping must be 0 (OpenSim ignores one below 0.001)");
  if (!damped_ && p.activation_floor < kUndampedMinimumActivation)
    reject(p, "activation_floor", p.activation_floor,
           "OpenSim's undamped elastic-tendon model needs minimum_activation >= 0.01");
  require_strain(p, "tendon_strain_at_max_force", p.tendon_strain_at_max_force,
                 parameters_.tendon_force_length.strain_at_one_norm_force, "TendonForceLengthCurve");
  require_strain(p, "passive_fiber_strain_at_one_norm_force", p.passive_fiber_strain_at_one_norm_force,
                 parameters_.fiber_force_length.strain_at_one_norm_force, "FiberForceLengthCurve");
}

std::string Millard2012Muscle::slopeJumps() const {
  if (!damped_) return "activation time constant switches at n = a";
  return "activation time constant switches at n = a, and the forward model's inverse of the force-velocity curve "
         "turns from an infinite slope to its straight continuation at force ratios 0 and fmax";
}

double Millard2012Muscle::minimumFiberLength(const MuscleParameters& p) const {
  // SimTK::SignificantReal = eps^(7/8); the pennation model's floor is the fibre at its maximum
  // angle, or 1% of the optimal length when that is 0.
  const double significant = std::pow(kEps, 7.0 / 8.0);
  const double lopt = p.optimal_fiber_length_m;
  const double active = parameters_.active_force_length.min_norm_active_fiber_length * lopt;
  const double pennated = maximum_pennation_angle_rad_ > significant
                              ? p.fiber_thickness_m() / std::sin(maximum_pennation_angle_rad_)
                              : 0.01 * lopt;
  return std::max({significant, active, pennated});
}

// ---------------------------------------------------------------- tendon
CurveJet Millard2012Muscle::tendonForce(const MuscleParameters& p, double tendon_length_m) const {
  const double slack = p.tendon_slack_length_m;
  return scaled(curves_.tendon_force_length.evaluate(tendon_length_m / slack), p.max_isometric_force_N, slack);
}

double Millard2012Muscle::tendonForceThirdDerivative(const MuscleParameters& p, double tendon_length_m) const {
  const double slack = p.tendon_slack_length_m;
  return p.max_isometric_force_N * curves_.tendon_force_length.evaluate(tendon_length_m / slack).third /
         (slack * slack * slack);
}

double Millard2012Muscle::tendonLengthFromForce(const MuscleParameters& p, double tendon_force_N) const {
  if (!std::isfinite(tendon_force_N) || tendon_force_N <= 0.0)
    detail::domain_failure(p, "tendon length is defined only for a finite tendon force > 0 N", tendon_force_N);
  return p.tendon_slack_length_m * curves_.tendon_force_length.inverse(tendon_force_N / p.max_isometric_force_N);
}

// ---------------------------------------------------------------- fibre
CurveJet Millard2012Muscle::activeForceLength(const MuscleParameters& p, double fiber_length_m) const {
  const double lopt = p.optimal_fiber_length_m;
  return scaled(curves_.active_force_length.evaluate(fiber_length_m / lopt), 1.0, lopt);
}

CurveJet Millard2012Muscle::passiveFiberForce(const MuscleParameters& p, double fiber_length_m) const {
  const double lopt = p.optimal_fiber_length_m;
  return scaled(curves_.fiber_force_length.evaluate(fiber_length_m / lopt), p.max_isometric_force_N, lopt);
}

CurveJet Millard2012Muscle::forceVelocity(const MuscleParameters& p, double u) const {
  // OpenSim's x is the lengthening velocity in maximum velocities: x = -u / Vmax.
  const double vmax = p.max_shortening_velocity_m_per_s();
  return scaled(velocity_curve_.evaluate(-u / vmax), 1.0, -vmax);
}

double Millard2012Muscle::forceVelocityInverse(const MuscleParameters& p, double z) const {
  if (!std::isfinite(z)) detail::domain_failure(p, "force-velocity inverse needs a finite force ratio", z);
  if (damped_ && !(z > 0.0 && z < velocity_curve_.y_end()))
    detail::domain_failure(p,
                           "the damped Millard force-velocity curve is flat beyond +-Vmax: its inverse is unique "
                           "only for force ratios in (0, max_eccentric_velocity_force_multiplier)",
                           z);
  return -p.max_shortening_velocity_m_per_s() * velocity_curve_.inverse(z);
}

double Millard2012Muscle::forceRatioExactUpperBound(const MuscleParameters&) const {
  // Damped: every u <= -Vmax gives fmax, so the forward model can be exact only below it.
  return damped_ ? std::nextafter(velocity_curve_.y_end(), 0.0) : std::numeric_limits<double>::infinity();
}

CurveJet Millard2012Muscle::fiberVelocityFromForceRatio(const MuscleParameters& p, double z) const {
  if (damped_) return flatEndInverse(p, z);
  // OpenSim's ForceVelocityInverseCurve: g's axes swapped, linear beyond its ends. (Its second
  // derivative is not part of the seam.)
  const double vmax = p.max_shortening_velocity_m_per_s();
  const BezierCurveJet v = curves_.force_velocity_inverse.evaluate(z);
  return {-vmax * v.value, -vmax * v.first, 0.0};
}

CurveJet Millard2012Muscle::flatEndInverse(const MuscleParameters& p, double z) const {
  const double vmax = p.max_shortening_velocity_m_per_s(), fmax = velocity_curve_.y_end();
  const double continuation = flatEndContinuationSlope();
  double lengthening = 0.0, slope = 1.0 / continuation;  // x and dx/dz, x = -u / Vmax
  if (z <= 0.0) {
    lengthening = -1.0 + z / continuation;
  } else if (z >= fmax) {
    lengthening = 1.0 + (z - fmax) / continuation;
  } else {
    lengthening = velocity_curve_.inverse(z);
    // The exact slope 1 / fV'(x), finite wherever fV' > 0 (all of (-1, 1)); only a slope that
    // rounds to 0 next to an end takes the continuation's.
    const double curve_slope = velocity_curve_.evaluate(lengthening).first;
    if (curve_slope > 0.0) slope = 1.0 / curve_slope;
  }
  return {-vmax * lengthening, -vmax * slope, 0.0};
}

// ---------------------------------------------------------------- activation
ActivationRate Millard2012Muscle::activationRate(const MuscleParameters& p, double excitation, double activation) const {
  return detail::first_order_activation_rate(p, excitation, activation);
}

ExcitationFromActivation Millard2012Muscle::excitationFromActivation(const MuscleParameters& p, double activation,
                                                                     double rate) const {
  return detail::first_order_excitation_from_activation(p, activation, rate);
}

ExcitationBoundMargins Millard2012Muscle::excitationBoundMargins(const MuscleParameters& p, double activation,
                                                                 double rate) const {
  return detail::first_order_excitation_bound_margins(p, activation, rate);
}

}  // namespace flatsos::muscles
