#pragma once
// The muscle curves of Millard et al. (2013), "Flexing computational muscle: modeling and
// simulation of musculotendon dynamics", J Biomech Eng 135(2):021005, built as OpenSim 4 builds
// them for Millard2012EquilibriumMuscle: C2 chains of quintic Bezier corners
// (quintic_bezier_curve.hpp) from a few properties. Field names are OpenSim's property names;
// defaults are OpenSim's. Every x and y here is normalised, hence dimensionless:
//   active and passive fibre force-length: x = fibre length / optimal fibre length;
//   force-velocity: x = fibre LENGTHENING velocity / (max contraction velocity x optimal fibre
//     length), so -1 is the fastest shortening (force 0), 0 isometric (force 1), +1 the fastest
//     lengthening (force max_eccentric_velocity_force_multiplier);
//   tendon force-length: x = tendon length / tendon slack length;
//   y = force / max isometric force (force-velocity: the multiplier).
// Unset optional properties (std::nullopt) get OpenSim's computed defaults; as in OpenSim, a
// curve's optional properties must be all set or all unset. Bad properties throw
// std::invalid_argument naming the curve and the property.
//
// Standalone: nothing here depends on MuscleModel or MuscleParameters.

#include <optional>

#include "flatsos/muscles/quintic_bezier_curve.hpp"

namespace flatsos::muscles {

/// OpenSim ActiveForceLengthCurve. The curve peaks at 1 at normalised length 1 and is
/// minimum_value at and beyond min_norm_active_fiber_length and max_norm_active_fiber_length.
struct ActiveForceLengthCurveProperties {
  double min_norm_active_fiber_length = 0.47 - 0.0259;  ///< where the steep ascending limb starts
  double transition_norm_fiber_length = 0.73;           ///< steep -> shallow ascending limb
  double max_norm_active_fiber_length = 1.8123;         ///< where the descending limb ends
  double shallow_ascending_slope = 0.8616;
  double minimum_value = 0.1;
};

/// OpenSim ForceVelocityCurve (x: normalised lengthening velocity, see above).
struct ForceVelocityCurveProperties {
  double concentric_slope_at_vmax = 0.0;
  double concentric_slope_near_vmax = 0.25;  ///< at x = -0.9
  double isometric_slope = 5.0;
  double eccentric_slope_at_vmax = 0.0;
  double eccentric_slope_near_vmax = 0.15;  ///< at x = +0.9
  double max_eccentric_velocity_force_multiplier = 1.4;
  double concentric_curviness = 0.6;
  double eccentric_curviness = 0.9;
};

/// The properties OpenSim's stand-alone ForceVelocityInverseCurve defaults to: those of the
/// force-velocity curve but with nonzero end slopes (the inverse's end slopes are their
/// reciprocals).
ForceVelocityCurveProperties force_velocity_inverse_curve_defaults();

/// OpenSim FiberForceLengthCurve (passive fibre). Unset: stiffness_at_low_force 0.2,
/// stiffness_at_one_norm_force 2 / (strain_at_one_norm_force - strain_at_zero_force),
/// curviness 0.75.
struct FiberForceLengthCurveProperties {
  double strain_at_zero_force = 0.0;
  double strain_at_one_norm_force = 0.7;
  std::optional<double> stiffness_at_low_force;
  std::optional<double> stiffness_at_one_norm_force;
  std::optional<double> curviness;
};

/// OpenSim TendonForceLengthCurve. Unset: stiffness_at_one_norm_force
/// 1.375 / strain_at_one_norm_force, norm_force_at_toe_end 2/3, curviness 0.5.
struct TendonForceLengthCurveProperties {
  double strain_at_one_norm_force = 0.049;
  std::optional<double> stiffness_at_one_norm_force;
  std::optional<double> norm_force_at_toe_end;
  std::optional<double> curviness;
};

/// OpenSim FiberCompressiveForceLengthCurve (x: normalised fibre length; 1 at x = 0, 0 from
/// norm_length_at_zero_force on). Unset: stiffness_at_zero_length -2 / norm_length_at_zero_force,
/// curviness 0.5.
struct FiberCompressiveForceLengthCurveProperties {
  double norm_length_at_zero_force = 0.5;
  std::optional<double> stiffness_at_zero_length;
  std::optional<double> curviness;
};

/// OpenSim FiberCompressiveForceCosPennationCurve (x: cos of the pennation angle; 1 at x = 0,
/// 0 from cos(engagement angle) on). Unset: stiffness_at_perpendicular -2 / cos(engagement angle),
/// curviness 0.1. The angle keeps OpenSim's name and unit (degrees) so files map one to one.
struct FiberCompressiveForceCosPennationCurveProperties {
  double engagement_angle_in_degrees = 85.0;
  std::optional<double> stiffness_at_perpendicular;
  std::optional<double> curviness;
};

/// Every curve property of one Millard2012EquilibriumMuscle, OpenSim's defaults throughout.
struct Millard2012CurveParameters {
  ActiveForceLengthCurveProperties active_force_length;
  ForceVelocityCurveProperties force_velocity;
  FiberForceLengthCurveProperties fiber_force_length;
  TendonForceLengthCurveProperties tendon_force_length;
  FiberCompressiveForceLengthCurveProperties fiber_compressive_force_length;
  FiberCompressiveForceCosPennationCurveProperties fiber_compressive_force_cos_pennation;
};

// ---- The optional properties OpenSim would use ("...InUse"): given values or its defaults.
FiberForceLengthCurveProperties resolved(const FiberForceLengthCurveProperties& properties);
TendonForceLengthCurveProperties resolved(const TendonForceLengthCurveProperties& properties);
FiberCompressiveForceLengthCurveProperties resolved(
    const FiberCompressiveForceLengthCurveProperties& properties);
FiberCompressiveForceCosPennationCurveProperties resolved(
    const FiberCompressiveForceCosPennationCurveProperties& properties);

// ---- Each curve as OpenSim's SmoothSegmentedFunctionFactory builds it.
QuinticBezierCurve active_force_length_curve(const ActiveForceLengthCurveProperties& properties);
QuinticBezierCurve force_velocity_curve(const ForceVelocityCurveProperties& properties);
/// OpenSim's ForceVelocityInverseCurve: the force-velocity curve of the same properties with its
/// axes swapped, hence its exact inverse (x: force multiplier, y: normalised lengthening
/// velocity). Needs both slopes at vmax > 0 (OpenSim's check), so that its end slopes are finite.
QuinticBezierCurve force_velocity_inverse_curve(const ForceVelocityCurveProperties& properties);
QuinticBezierCurve fiber_force_length_curve(const FiberForceLengthCurveProperties& properties);
QuinticBezierCurve tendon_force_length_curve(const TendonForceLengthCurveProperties& properties);
QuinticBezierCurve fiber_compressive_force_length_curve(
    const FiberCompressiveForceLengthCurveProperties& properties);
QuinticBezierCurve fiber_compressive_force_cos_pennation_curve(
    const FiberCompressiveForceCosPennationCurveProperties& properties);

/// How a Millard2012EquilibriumMuscle is configured; it changes the curves it builds.
struct Millard2012MuscleConfiguration {
  double fiber_damping = 0.1;             ///< OpenSim's default; below 0.001 it means none
  bool ignore_tendon_compliance = false;  ///< rigid tendon
};

/// The curve properties a Millard2012EquilibriumMuscle actually uses
/// (extendFinalizeFromProperties). Damped elastic tendon or rigid tendon: minimum_value and
/// both slopes at vmax raised or lowered to 0 where they are positive. Undamped elastic tendon:
/// minimum_value at least 0.1 and each slope at vmax at least half its slope near vmax.
/// Throws std::invalid_argument if a slope near vmax is below sqrt(eps) (OpenSim's check).
Millard2012CurveParameters millard2012_muscle_curve_parameters(
    const Millard2012CurveParameters& parameters,
    const Millard2012MuscleConfiguration& configuration);

/// The curves of one Millard2012EquilibriumMuscle.
struct Millard2012Curves {
  QuinticBezierCurve active_force_length;
  QuinticBezierCurve force_velocity;
  /// Built as the muscle builds it: from the force-velocity properties with each slope at vmax
  /// replaced by half the slope near vmax. The knots at +-0.9 depend on the slopes at vmax, so
  /// this is the exact inverse of force_velocity only when force_velocity's slopes at vmax are
  /// already half its near ones (the undamped model with OpenSim's defaults). Otherwise the two
  /// agree only at velocities -1, 0 and +1 (with OpenSim's damped defaults they differ by up to
  /// 0.026 normalised velocity); OpenSim's damped model uses this curve only to start Newton.
  QuinticBezierCurve force_velocity_inverse;
  QuinticBezierCurve fiber_force_length;
  QuinticBezierCurve tendon_force_length;
};

/// The muscle's curves from properties it already uses (apply
/// millard2012_muscle_curve_parameters first to reproduce OpenSim's adjustments).
Millard2012Curves millard2012_curves(const Millard2012CurveParameters& parameters);

}  // namespace flatsos::muscles
