// The Millard (2013) curve properties: OpenSim's computed defaults for unset optional
// properties, its range checks, and the adjustments Millard2012EquilibriumMuscle makes to its
// curves for the damped, undamped and rigid-tendon formulations (OpenSim 4 source).
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "millard2012_curve_checks.hpp"

namespace flatsos::muscles {
namespace {

using detail::kPi;
const double kRootEps = std::sqrt(std::numeric_limits<double>::epsilon());
// SimTK::SignificantReal = eps^(7/8): OpenSim's floor for slopes that must be nonzero.
const double kSignificantReal = std::pow(std::numeric_limits<double>::epsilon(), 7.0 / 8.0);

void require(bool holds, const char* curve, const char* property, double value,
             const std::string& requirement) {
  if (holds && std::isfinite(value)) return;
  std::ostringstream message;
  message << "OpenSim " << curve << ": " << property << " = " << value << " must be finite and "
          << requirement;
  throw std::invalid_argument(message.str());
}

void require_curviness(const char* curve, const char* property, double curviness) {
  require(curviness >= 0.0 && curviness <= 1.0, curve, property, curviness, "in [0, 1]");
}

/// OpenSim's rule for optional properties: all set, or all unset (then computed).
template <class... Optional>
bool all_unset(const char* curve, const Optional&... optional) {
  const int set = (int(optional.has_value()) + ...);
  if (set != 0 && set != int(sizeof...(Optional))) {
    throw std::invalid_argument(std::string("OpenSim ") + curve +
                                ": its optional properties must be all set or all unset");
  }
  return set == 0;
}

}  // namespace

ForceVelocityCurveProperties force_velocity_inverse_curve_defaults() {
  ForceVelocityCurveProperties properties;
  properties.concentric_slope_at_vmax = 0.1;
  properties.eccentric_slope_at_vmax = 0.1;
  return properties;
}

FiberForceLengthCurveProperties resolved(const FiberForceLengthCurveProperties& properties) {
  FiberForceLengthCurveProperties in_use = properties;
  if (all_unset("FiberForceLengthCurve", properties.stiffness_at_low_force,
                properties.stiffness_at_one_norm_force, properties.curviness)) {
    in_use.stiffness_at_low_force = 0.2;
    in_use.stiffness_at_one_norm_force =
        2.0 / (properties.strain_at_one_norm_force - properties.strain_at_zero_force);
    in_use.curviness = 0.75;
  }
  return in_use;
}

TendonForceLengthCurveProperties resolved(const TendonForceLengthCurveProperties& properties) {
  TendonForceLengthCurveProperties in_use = properties;
  if (all_unset("TendonForceLengthCurve", properties.stiffness_at_one_norm_force,
                properties.norm_force_at_toe_end, properties.curviness)) {
    in_use.stiffness_at_one_norm_force = 1.375 / properties.strain_at_one_norm_force;
    in_use.norm_force_at_toe_end = 2.0 / 3.0;
    in_use.curviness = 0.5;
  }
  return in_use;
}

FiberCompressiveForceLengthCurveProperties resolved(
    const FiberCompressiveForceLengthCurveProperties& properties) {
  FiberCompressiveForceLengthCurveProperties in_use = properties;
  if (all_unset("FiberCompressiveForceLengthCurve", properties.stiffness_at_zero_length,
                properties.curviness)) {
    in_use.stiffness_at_zero_length = -2.0 / properties.norm_length_at_zero_force;
    in_use.curviness = 0.5;
  }
  return in_use;
}

FiberCompressiveForceCosPennationCurveProperties resolved(
    const FiberCompressiveForceCosPennationCurveProperties& properties) {
  FiberCompressiveForceCosPennationCurveProperties in_use = properties;
  if (all_unset("FiberCompressiveForceCosPennationCurve", properties.stiffness_at_perpendicular,
                properties.curviness)) {
    in_use.stiffness_at_perpendicular =
        -2.0 / std::cos(properties.engagement_angle_in_degrees * kPi / 180.0);
    in_use.curviness = 0.1;
  }
  return in_use;
}

Millard2012CurveParameters millard2012_muscle_curve_parameters(
    const Millard2012CurveParameters& parameters,
    const Millard2012MuscleConfiguration& configuration) {
  Millard2012CurveParameters in_use = parameters;
  ActiveForceLengthCurveProperties& active = in_use.active_force_length;
  ForceVelocityCurveProperties& velocity = in_use.force_velocity;
  require(velocity.concentric_slope_near_vmax >= kRootEps, "ForceVelocityCurve",
          "concentric_slope_near_vmax", velocity.concentric_slope_near_vmax,
          "at least sqrt(eps) in a Millard2012EquilibriumMuscle");
  require(velocity.eccentric_slope_near_vmax >= kRootEps, "ForceVelocityCurve",
          "eccentric_slope_near_vmax", velocity.eccentric_slope_near_vmax,
          "at least sqrt(eps) in a Millard2012EquilibriumMuscle");
  const bool damped = configuration.fiber_damping >= 0.001;
  if (!configuration.ignore_tendon_compliance && !damped) {
    // The classic formulation divides by a f_L and inverts f_V: keep both away from 0.
    active.minimum_value = std::max(active.minimum_value, 0.1);
    velocity.concentric_slope_at_vmax =
        std::max(velocity.concentric_slope_at_vmax, 0.5 * velocity.concentric_slope_near_vmax);
    velocity.eccentric_slope_at_vmax =
        std::max(velocity.eccentric_slope_at_vmax, 0.5 * velocity.eccentric_slope_near_vmax);
  } else {
    active.minimum_value = std::min(active.minimum_value, 0.0);
    velocity.concentric_slope_at_vmax = std::min(velocity.concentric_slope_at_vmax, 0.0);
    velocity.eccentric_slope_at_vmax = std::min(velocity.eccentric_slope_at_vmax, 0.0);
  }
  return in_use;
}

namespace detail {

void check(const ActiveForceLengthCurveProperties& p) {
  const char* curve = "ActiveForceLengthCurve";
  require(p.min_norm_active_fiber_length >= 0.0, curve, "min_norm_active_fiber_length",
          p.min_norm_active_fiber_length, ">= 0");
  require(p.transition_norm_fiber_length > p.min_norm_active_fiber_length + kRootEps, curve,
          "transition_norm_fiber_length", p.transition_norm_fiber_length,
          "> min_norm_active_fiber_length");
  require(1.0 > p.transition_norm_fiber_length + kRootEps, curve, "transition_norm_fiber_length",
          p.transition_norm_fiber_length, "< 1 (the optimal length)");
  require(p.max_norm_active_fiber_length > 1.0 + kRootEps, curve, "max_norm_active_fiber_length",
          p.max_norm_active_fiber_length, "> 1 (the optimal length)");
  require(p.minimum_value >= 0.0, curve, "minimum_value", p.minimum_value, ">= 0");
  const double steepest = (1.0 - p.minimum_value) / (1.0 - p.transition_norm_fiber_length);
  require(p.shallow_ascending_slope >= 0.0 && p.shallow_ascending_slope < steepest, curve,
          "shallow_ascending_slope", p.shallow_ascending_slope,
          "in [0, (1 - minimum_value) / (1 - transition_norm_fiber_length))");
}

namespace {

void check_force_velocity_common(const ForceVelocityCurveProperties& p, const char* curve) {
  const double f_max = p.max_eccentric_velocity_force_multiplier;
  require(f_max > 1.0, curve, "max_eccentric_velocity_force_multiplier", f_max, "> 1");
  require(p.isometric_slope > 1.0, curve, "isometric_slope", p.isometric_slope, "> 1");
  require(p.eccentric_slope_near_vmax >= p.eccentric_slope_at_vmax &&
              p.eccentric_slope_near_vmax < f_max - 1.0,
          curve, "eccentric_slope_near_vmax", p.eccentric_slope_near_vmax,
          "in [eccentric_slope_at_vmax, max_eccentric_velocity_force_multiplier - 1)");
  require_curviness(curve, "concentric_curviness", p.concentric_curviness);
  require_curviness(curve, "eccentric_curviness", p.eccentric_curviness);
}

}  // namespace

void check_force_velocity(const ForceVelocityCurveProperties& p) {
  const char* curve = "ForceVelocityCurve";
  check_force_velocity_common(p, curve);
  require(p.concentric_slope_at_vmax >= 0.0 && p.concentric_slope_at_vmax < 1.0, curve,
          "concentric_slope_at_vmax", p.concentric_slope_at_vmax, "in [0, 1)");
  require(p.concentric_slope_near_vmax > p.concentric_slope_at_vmax &&
              p.concentric_slope_near_vmax <= 1.0,
          curve, "concentric_slope_near_vmax", p.concentric_slope_near_vmax,
          "in (concentric_slope_at_vmax, 1]");
  require(p.eccentric_slope_at_vmax >= 0.0 &&
              p.eccentric_slope_at_vmax < p.max_eccentric_velocity_force_multiplier - 1.0,
          curve, "eccentric_slope_at_vmax", p.eccentric_slope_at_vmax,
          "in [0, max_eccentric_velocity_force_multiplier - 1)");
}

void check_force_velocity_inverse(const ForceVelocityCurveProperties& p) {
  const char* curve = "ForceVelocityInverseCurve";
  check_force_velocity_common(p, curve);
  require(p.concentric_slope_at_vmax > kSignificantReal && p.concentric_slope_at_vmax < 1.0, curve,
          "concentric_slope_at_vmax", p.concentric_slope_at_vmax,
          "in (0, 1): the inverse's end slope is 1 / it");
  require(p.concentric_slope_near_vmax > p.concentric_slope_at_vmax &&
              p.concentric_slope_near_vmax < 1.0,
          curve, "concentric_slope_near_vmax", p.concentric_slope_near_vmax,
          "in (concentric_slope_at_vmax, 1)");
  require(p.eccentric_slope_at_vmax > kSignificantReal &&
              p.eccentric_slope_at_vmax < p.max_eccentric_velocity_force_multiplier - 1.0,
          curve, "eccentric_slope_at_vmax", p.eccentric_slope_at_vmax,
          "in (0, max_eccentric_velocity_force_multiplier - 1): the inverse's end slope is 1 / it");
}

void check(const FiberForceLengthCurveProperties& p) {
  const char* curve = "FiberForceLengthCurve";
  require(std::isfinite(p.strain_at_zero_force), curve, "strain_at_zero_force",
          p.strain_at_zero_force, "a number");
  const double span = p.strain_at_one_norm_force - p.strain_at_zero_force;
  require(span > 0.0, curve, "strain_at_one_norm_force", p.strain_at_one_norm_force,
          "> strain_at_zero_force");
  require(*p.stiffness_at_one_norm_force > 1.0 / span, curve, "stiffness_at_one_norm_force",
          *p.stiffness_at_one_norm_force,
          "> 1 / (strain_at_one_norm_force - strain_at_zero_force)");
  require(*p.stiffness_at_low_force > 0.0 && *p.stiffness_at_low_force < 1.0 / span, curve,
          "stiffness_at_low_force", *p.stiffness_at_low_force,
          "in (0, 1 / (strain_at_one_norm_force - strain_at_zero_force))");
  require_curviness(curve, "curviness", *p.curviness);
}

void check(const TendonForceLengthCurveProperties& p) {
  const char* curve = "TendonForceLengthCurve";
  require(p.strain_at_one_norm_force > 0.0, curve, "strain_at_one_norm_force",
          p.strain_at_one_norm_force, "> 0");
  require(*p.norm_force_at_toe_end > 0.0 && *p.norm_force_at_toe_end < 1.0, curve,
          "norm_force_at_toe_end", *p.norm_force_at_toe_end, "in (0, 1)");
  require(*p.stiffness_at_one_norm_force > 1.0 / p.strain_at_one_norm_force, curve,
          "stiffness_at_one_norm_force", *p.stiffness_at_one_norm_force,
          "> 1 / strain_at_one_norm_force");
  require_curviness(curve, "curviness", *p.curviness);
}

void check(const FiberCompressiveForceLengthCurveProperties& p) {
  const char* curve = "FiberCompressiveForceLengthCurve";
  require(p.norm_length_at_zero_force > 0.0, curve, "norm_length_at_zero_force",
          p.norm_length_at_zero_force, "> 0");
  require(*p.stiffness_at_zero_length < -1.0 / p.norm_length_at_zero_force, curve,
          "stiffness_at_zero_length", *p.stiffness_at_zero_length,
          "< -1 / norm_length_at_zero_force");
  require_curviness(curve, "curviness", *p.curviness);
}

void check(const FiberCompressiveForceCosPennationCurveProperties& p) {
  const char* curve = "FiberCompressiveForceCosPennationCurve";
  const double cos_engagement = std::cos(p.engagement_angle_in_degrees * kPi / 180.0);
  require(cos_engagement > 0.0 && cos_engagement < 1.0, curve, "engagement_angle_in_degrees",
          p.engagement_angle_in_degrees, "such that its cosine is in (0, 1)");
  // OpenSim checks k < 1 / cos(angle); the corner check then rejects k > -1 / cos(angle).
  require(*p.stiffness_at_perpendicular < 1.0 / cos_engagement, curve, "stiffness_at_perpendicular",
          *p.stiffness_at_perpendicular, "< 1 / cos(engagement angle)");
  require_curviness(curve, "curviness", *p.curviness);
}

}  // namespace detail
}  // namespace flatsos::muscles
