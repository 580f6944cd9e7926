// A path segment over an ellipsoid, as OpenSim's WrapEllipsoid::wrapLine computes it (SIMM's:
// Delp and Loan 2000, with Frans' axial plane and the "fan" of closest points): work in units
// where the semi-axes sum to 3; wrap only when the segment crosses the surface; pick a surface
// point c1 that fixes the wrapping plane through p1 and p2; find the tangent points in that
// plane; measure OpenSim's polyline between them, round the far side when the near side runs
// the wrong way. Kept as OpenSim runs it: the mirror of c1 onto the active side pulls c1 back
// towards the cutting plane only when the fan took part (OpenSim's test for "no fan weight yet"
// compares -inf with itself through a difference, which is NaN, so it never fires).

#include <algorithm>
#include <cmath>
#include <limits>

#include "ellipsoid_geometry.hpp"
#include "flatsos/plugin/paths/wrap_surfaces.hpp"

namespace flatsos::plugin {

namespace {

using namespace wrap_math;

constexpr double kFanOnly = 0.7073;    // below: the fan alone (must exceed cos 45 deg)
constexpr double kAxialOnly = 0.9;     // above: Frans' axial plane alone
constexpr int kFanSamples = 300;
constexpr double kEndFade = 0.3;       // fade Frans' point out near the chord's ends

struct PlanePoint {
  Vec3 c1 = Vec3::Zero();
  double t_axial = kNaN;  // where the chord crosses the most aligned axis' zero plane
  double fan_weight = -std::numeric_limits<double>::infinity();  // unset
};

// The fan: average direction from chord points to their closest surface points.
Vec3 fan_point(const Vec3& r1, const Vec3& chord, const Vec3& a) {
  Vec3 sum = Vec3::Zero();
  for (int i = 1; i < kFanSamples - 1; ++i) {
    const Vec3 s = r1 + (static_cast<double>(i) / kFanSamples) * chord;
    sum += unit_or_zero(ellipsoid::closest_point(a, s) - s);
  }
  return ellipsoid::closest_point(a, Vec3(r1 + 0.5 * chord + unit_or_zero(sum)));
}

// OpenSim's choice of c1 from the chord r1 r2 (the segment's intersections with the surface).
PlanePoint wrapping_plane_point(const Vec3& r1, const Vec3& r2, const Vec3& p1p2, const Vec3& a, WrapMethod method) {
  PlanePoint out;
  const Vec3 chord = r2 - r1;
  const Vec3 alignment = unit_or_zero(p1p2).cwiseAbs();
  int axis = 0;
  for (int i = 1; i < 3; ++i)
    if (alignment[i] > alignment[axis]) axis = i;
  out.t_axial = (0.0 - r1[axis]) / chord[axis];
  if (method == WrapMethod::Midpoint) {
    out.c1 = ellipsoid::closest_point(a, Vec3(r1 + 0.5 * (r2 - r1)));
    return out;
  }
  const Vec3 axial_c1 = ellipsoid::closest_point(a, Vec3(r1 + out.t_axial * chord), axis);
  double mu = alignment[axis];
  if (method == WrapMethod::Hybrid && mu > kFanOnly) {
    const double t = out.t_axial;
    double s = 1.0;
    if (t < 0.0 || t > 1.0)
      s = 0.0;
    else if (t < kEndFade)
      s = t / kEndFade;
    else if (t > 1.0 - kEndFade)
      s = (1.0 - t) / kEndFade;
    if (s < 1.0) mu = kFanOnly + s * (mu - kFanOnly);
  }
  if (method == WrapMethod::Axial || mu > kFanOnly) out.c1 = axial_c1;
  if (method == WrapMethod::Hybrid && mu < kAxialOnly) {
    const Vec3 fan_c1 = fan_point(r1, chord, a);
    if (mu <= kFanOnly) {
      out.c1 = fan_c1;  // OpenSim projects the fan's guess once: fan_point already did
      out.fan_weight = 1.0;
    } else {
      const double w = (mu - kFanOnly) / (kAxialOnly - kFanOnly);
      out.c1 = ellipsoid::closest_point(a, Vec3(w * out.c1 + (1.0 - w) * fan_c1));
      out.fan_weight = 1.0 - w;
    }
  }
  return out;
}

// A constrained ellipsoid: mirror c1 onto the active side (tangent search starts there), then
// pull it towards the cutting plane by the fan's weight.
void move_to_active_side(WrapQuadrant q, const Vec3& a, PlanePoint& plane, Vec3& r1, Vec3& r2) {
  if (q.sign == 0 || sign_of(plane.c1[q.axis]) == q.sign) return;
  const double original = plane.c1[q.axis];
  plane.c1[q.axis] = -plane.c1[q.axis];
  r1 = r2 = plane.c1;
  const double weight = std::min(plane.fan_weight, 1.0);
  if (weight > 0.0) {
    const double middle = (original + plane.c1[q.axis]) / 2.0;
    plane.c1[q.axis] += weight * (middle - plane.c1[q.axis]);
    plane.c1 = ellipsoid::closest_point(a, plane.c1);
  }
}

double level(const Vec3& p, const Vec3& a) {
  double out = -1.0;
  for (int i = 0; i < 3; ++i) out += (p[i] / a[i]) * (p[i] / a[i]);
  return out;
}

}  // namespace

WrapLineResult wrap_ellipsoid_line(const Vec3& P1, const Vec3& P2, const Vec3& dimensions_m, WrapQuadrant quadrant, WrapMethod method,
                                   std::vector<Vec3>* surface_points) {
  WrapLineResult out;
  const double factor = 3.0 / dimensions_m.sum();
  const Vec3 p1 = P1 * factor, p2 = P2 * factor, a = dimensions_m * factor;
  const double p1_level = level(p1, a), p2_level = level(p2, a);
  if (p1_level < -1e-4 || p2_level < -1e-4) {
    out.action = WrapAction::InsideRadius;
    return out;
  }
  const Vec3 p1p2 = p1 - p2;
  if (std::abs(unit_or_zero(p1).dot(unit_or_zero(p2)) - 1.0) < 1e-4) return out;  // ends in line with the centre
  const Vec3 f1 = p1p2.cwiseQuotient(a), f2 = p2.cwiseQuotient(a);
  const double qa = f1.dot(f1), qb = 2.0 * f1.dot(f2), qc = f2.dot(f2) - 1.0;
  const double discriminant = qb * qb - 4.0 * qa * qc;
  if (discriminant < 0.0) return out;
  const double l1 = (-qb + std::sqrt(discriminant)) / (2.0 * qa), l2 = (-qb - std::sqrt(discriminant)) / (2.0 * qa);
  if (!(0.0 < l1 && l1 < 1.0) || !(0.0 < l2 && l2 < 1.0)) return out;
  Vec3 r1 = p2 + l1 * p1p2, r2 = p2 + l2 * p1p2;

  PlanePoint plane = wrapping_plane_point(r1, r2, p1p2, a, method);
  if (method != WrapMethod::Axial || (plane.t_axial > 0.0 && plane.t_axial < 1.0)) r1 = r2 = plane.c1;
  move_to_active_side(quadrant, a, plane, r1, r2);
  const Vec3 vs = unit_or_zero(p1p2.cross(p1 - plane.c1));
  const double vs4 = -vs.dot(plane.c1);
  ellipsoid::tangent_point(p1_level, p1, a, vs, vs4, r1);
  ellipsoid::tangent_point(p2_level, p2, a, vs, vs4, r2);

  ellipsoid::Polyline path = ellipsoid::surface_polyline(r1, r2, a, vs, vs4, false, factor, surface_points);
  if (quadrant.sign != 0 && path.point_count > 2) {
    // The wrong way round: the first or last chord turns back towards its end point.
    const bool back1 = unit_or_zero(p1 - r1).dot(unit_or_zero(path.first_interior - r1)) > 0.0;
    const bool back2 = unit_or_zero(p2 - r2).dot(unit_or_zero(path.last_interior - r2)) > 0.0;
    if (back1 || back2) path = ellipsoid::surface_polyline(r1, r2, a, vs, vs4, true, factor, surface_points);
  }
  if (surface_points)
    for (Vec3& p : *surface_points) p /= factor;
  out.action = WrapAction::MandatoryWrap;
  out.surface_length_m = path.length / factor;
  out.r1 = r1 / factor;
  out.r2 = r2 / factor;
  return out;
}

}  // namespace flatsos::plugin
