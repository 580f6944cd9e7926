// Millard et al. (2013) muscle curves, constructed as OpenSim's SmoothSegmentedFunctionFactory
// places its quintic Bezier corners (J Biomech Eng 135(2):021005, Appendix; OpenSim 4 source).
// The property checks are OpenSim's, in millard2012_curve_properties.cpp.
#include "flatsos/muscles/millard2012_curves.hpp"

#include <algorithm>
#include <cmath>

#include "millard2012_curve_checks.hpp"

namespace flatsos::muscles {
namespace {

using detail::kPi;

/// The force-velocity corners in (velocity, force) order; the inverse swaps the axes.
std::vector<QuinticBezierSegment> force_velocity_segments(const ForceVelocityCurveProperties& p,
                                                          const char* curve) {
  const std::string what = std::string("OpenSim ") + curve;
  const double near_velocity = 0.9;  // where the near-vmax slopes hold, either side
  const double force_near_concentric =
      0.5 * (p.concentric_slope_near_vmax + p.concentric_slope_at_vmax) * (1.0 - near_velocity);
  const double force_max = p.max_eccentric_velocity_force_multiplier;
  const double force_near_eccentric =
      force_max -
      0.5 * (p.eccentric_slope_near_vmax + p.eccentric_slope_at_vmax) * (1.0 - near_velocity);
  return {
      quintic_bezier_corner(-1.0, 0.0, p.concentric_slope_at_vmax, -near_velocity,
                            force_near_concentric, p.concentric_slope_near_vmax,
                            p.concentric_curviness, what),
      quintic_bezier_corner(-near_velocity, force_near_concentric, p.concentric_slope_near_vmax,
                            0.0, 1.0, p.isometric_slope, p.concentric_curviness, what),
      quintic_bezier_corner(0.0, 1.0, p.isometric_slope, near_velocity, force_near_eccentric,
                            p.eccentric_slope_near_vmax, p.eccentric_curviness, what),
      quintic_bezier_corner(near_velocity, force_near_eccentric, p.eccentric_slope_near_vmax, 1.0,
                            force_max, p.eccentric_slope_at_vmax, p.eccentric_curviness, what)};
}

}  // namespace

QuinticBezierCurve active_force_length_curve(const ActiveForceLengthCurveProperties& p) {
  detail::check(p);
  const char* what = "OpenSim ActiveForceLengthCurve";
  const double start = p.min_norm_active_fiber_length, transition = p.transition_norm_fiber_length;
  const double optimum = 1.0, end = p.max_norm_active_fiber_length, floor = p.minimum_value;
  const double curviness = 1.0;  // fixed by ActiveForceLengthCurve
  // The plateau is widened by 5% of the optimal length either side of the peak.
  const double half_plateau = 0.05 * optimum;
  const double shoulder = optimum - half_plateau;
  // The steep ascending limb rises from 0 (not from minimum_value) to where the shallow one
  // would reach the shoulder; the steep limb's mid-point slope is 1.25 times its chord's.
  const double steep_top = 1.0 - p.shallow_ascending_slope * (shoulder - transition);
  const double steep_slope = 1.25 * steep_top / (transition - start);
  const double steep_mid_x = 0.5 * (start + transition), steep_mid_y = 0.5 * steep_top;
  const double shallow_mid_x = transition + 0.5 * (shoulder - transition);
  const double shallow_mid_y = steep_top + 0.5 * (1.0 - steep_top);
  const double descending_mid_x = (optimum + half_plateau) + 0.5 * (end - (optimum + half_plateau));
  const double descending_slope = -1.0 / ((end - half_plateau) - (optimum + half_plateau));
  return QuinticBezierCurve(
      {quintic_bezier_corner(start, floor, 0.0, steep_mid_x, steep_mid_y, steep_slope, curviness,
                             what),
       quintic_bezier_corner(steep_mid_x, steep_mid_y, steep_slope, shallow_mid_x, shallow_mid_y,
                             p.shallow_ascending_slope, curviness, what),
       quintic_bezier_corner(shallow_mid_x, shallow_mid_y, p.shallow_ascending_slope, optimum, 1.0,
                             0.0, curviness, what),
       quintic_bezier_corner(optimum, 1.0, 0.0, descending_mid_x, 0.5, descending_slope, curviness,
                             what),
       quintic_bezier_corner(descending_mid_x, 0.5, descending_slope, end, floor, 0.0, curviness,
                             what)},
      what, 0.0, 0.0);
}

QuinticBezierCurve force_velocity_curve(const ForceVelocityCurveProperties& p) {
  detail::check_force_velocity(p);
  return QuinticBezierCurve(force_velocity_segments(p, "ForceVelocityCurve"),
                            "OpenSim ForceVelocityCurve", p.concentric_slope_at_vmax,
                            p.eccentric_slope_at_vmax);
}

QuinticBezierCurve force_velocity_inverse_curve(const ForceVelocityCurveProperties& p) {
  detail::check_force_velocity_inverse(p);
  std::vector<QuinticBezierSegment> segments =
      force_velocity_segments(p, "ForceVelocityInverseCurve");
  for (QuinticBezierSegment& segment : segments) std::swap(segment.x, segment.y);
  return QuinticBezierCurve(std::move(segments), "OpenSim ForceVelocityInverseCurve",
                            1.0 / p.concentric_slope_at_vmax, 1.0 / p.eccentric_slope_at_vmax);
}

QuinticBezierCurve fiber_force_length_curve(const FiberForceLengthCurveProperties& properties) {
  const FiberForceLengthCurveProperties p = resolved(properties);
  detail::check(p);
  const char* what = "OpenSim FiberForceLengthCurve";
  const double k_low = *p.stiffness_at_low_force, k_one = *p.stiffness_at_one_norm_force;
  const double x_zero = 1.0 + p.strain_at_zero_force, x_one = 1.0 + p.strain_at_one_norm_force;
  // The low-force point sits a short way into the curve, on a line of slope k_low through the
  // foot halfway there.
  const double x_low = x_zero + std::min(0.1 / k_one, 0.1 * (x_one - x_zero));
  const double x_foot = x_zero + 0.5 * (x_low - x_zero);
  const double y_low = k_low * (x_low - x_foot);
  return QuinticBezierCurve(
      {quintic_bezier_corner(x_zero, 0.0, 0.0, x_low, y_low, k_low, *p.curviness, what),
       quintic_bezier_corner(x_low, y_low, k_low, x_one, 1.0, k_one, *p.curviness, what)},
      what, 0.0, k_one);
}

QuinticBezierCurve tendon_force_length_curve(const TendonForceLengthCurveProperties& properties) {
  const TendonForceLengthCurveProperties p = resolved(properties);
  detail::check(p);
  const char* what = "OpenSim TendonForceLengthCurve";
  const double k_one = *p.stiffness_at_one_norm_force, toe_force = *p.norm_force_at_toe_end;
  const double x_one = 1.0 + p.strain_at_one_norm_force;
  // The toe ends on the linear part (slope k_one through (x_one, 1)) at force toe_force.
  const double x_toe = x_one + (toe_force - 1.0) / k_one;
  // The toe's middle control point: on the line from the foot (a tenth of the way from slack to
  // the toe's end) to the linear part's point at half the toe force, halfway along it.
  const double x_foot = 1.0 + 0.1 * (x_toe - 1.0);
  const double y_toe_mid = 0.5 * toe_force;
  const double x_toe_mid = x_one + (y_toe_mid - 1.0) / k_one;
  const double toe_mid_slope = y_toe_mid / (x_toe_mid - x_foot);
  const double x_toe_control = x_foot + 0.5 * (x_toe_mid - x_foot);
  const double y_toe_control = toe_mid_slope * (x_toe_control - x_foot);
  return QuinticBezierCurve({quintic_bezier_corner(1.0, 0.0, 0.0, x_toe_control, y_toe_control,
                                                   toe_mid_slope, *p.curviness, what),
                             quintic_bezier_corner(x_toe_control, y_toe_control, toe_mid_slope,
                                                   x_toe, toe_force, k_one, *p.curviness, what)},
                            what, 0.0, k_one);
}

QuinticBezierCurve fiber_compressive_force_length_curve(
    const FiberCompressiveForceLengthCurveProperties& properties) {
  const FiberCompressiveForceLengthCurveProperties p = resolved(properties);
  detail::check(p);
  const char* what = "OpenSim FiberCompressiveForceLengthCurve";
  return QuinticBezierCurve(
      {quintic_bezier_corner(0.0, 1.0, *p.stiffness_at_zero_length, p.norm_length_at_zero_force,
                             0.0, 0.0, *p.curviness, what)},
      what, *p.stiffness_at_zero_length, 0.0);
}

QuinticBezierCurve fiber_compressive_force_cos_pennation_curve(
    const FiberCompressiveForceCosPennationCurveProperties& properties) {
  const FiberCompressiveForceCosPennationCurveProperties p = resolved(properties);
  detail::check(p);
  const char* what = "OpenSim FiberCompressiveForceCosPennationCurve";
  const double cos_engagement = std::cos(p.engagement_angle_in_degrees * kPi / 180.0);
  return QuinticBezierCurve({quintic_bezier_corner(0.0, 1.0, *p.stiffness_at_perpendicular,
                                                   cos_engagement, 0.0, 0.0, *p.curviness, what)},
                            what, *p.stiffness_at_perpendicular, 0.0);
}

Millard2012Curves millard2012_curves(const Millard2012CurveParameters& parameters) {
  ForceVelocityCurveProperties inverse_properties = parameters.force_velocity;
  inverse_properties.concentric_slope_at_vmax = 0.5 * inverse_properties.concentric_slope_near_vmax;
  inverse_properties.eccentric_slope_at_vmax = 0.5 * inverse_properties.eccentric_slope_near_vmax;
  return {active_force_length_curve(parameters.active_force_length),
          force_velocity_curve(parameters.force_velocity),
          force_velocity_inverse_curve(inverse_properties),
          fiber_force_length_curve(parameters.fiber_force_length),
          tendon_force_length_curve(parameters.tendon_force_length)};
}

}  // namespace flatsos::muscles
