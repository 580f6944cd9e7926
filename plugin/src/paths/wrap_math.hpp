#pragma once
// The small geometric helpers the wrap surfaces share, with the exact conventions of OpenSim's
// WrapMath (SIMM's): a "line" is a point and a direction that need not be unit, a vector
// shorter than machine epsilon normalises to zero, parallel lines intersect nowhere (NaN).

#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <cmath>
#include <limits>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace flatsos::plugin::wrap_math {

using Vec3 = Eigen::Vector3d;

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kPi = 3.14159265358979323846;

/// OpenSim's DSIGN: +1 for v >= 0 (and -1 for NaN).
inline int sign_of(double v) { return v >= 0.0 ? 1 : -1; }

/// v / |v| into `out`, or zero when |v| < machine epsilon; returns |v|.
inline double normalize_or_zero(const Vec3& v, Vec3& out) {
  const double magnitude = v.norm();
  if (magnitude >= std::numeric_limits<double>::epsilon())
    out = v / magnitude;
  else
    out.setZero();
  return magnitude;
}
inline Vec3 unit_or_zero(const Vec3& v) {
  Vec3 out;
  normalize_or_zero(v, out);
  return out;
}

/// The point of the line (line_point, direction) closest to `point`; `t` is its parameter in
/// units of |direction|.
inline Vec3 closest_point_on_line(const Vec3& point, const Vec3& line_point, const Vec3& direction, double* t = nullptr) {
  Vec3 to_point, unit_direction;
  const double distance = normalize_or_zero(point - line_point, to_point);
  const double direction_length = normalize_or_zero(direction, unit_direction);
  const double along = to_point.dot(unit_direction) * distance;
  if (t) *t = along / direction_length;
  return line_point + along * unit_direction;
}

inline double distance_squared_to_line(const Vec3& point, const Vec3& line_point, const Vec3& direction) {
  const Vec3 to_line = line_point - point;
  const Vec3 n = direction / direction.norm();
  return (to_line - to_line.dot(n) * n).squaredNorm();
}

/// Closest points of the lines p1 p2 and p3 p4: on the first at p1 + s (p2 - p1), on the
/// second at p3 + t (p4 - p3). Parallel lines (|cross|^2 <= 2e-13): false, NaN everywhere.
struct LineIntersection {
  Vec3 on_first = Vec3::Constant(kNaN), on_second = Vec3::Constant(kNaN);
  double s = kNaN, t = kNaN;
  bool found = false;
};
inline LineIntersection intersect_lines(const Vec3& p1, const Vec3& p2, const Vec3& p3, const Vec3& p4) {
  LineIntersection out;
  Vec3 u, v;
  const double length_u = normalize_or_zero(p2 - p1, u);
  const double length_v = normalize_or_zero(p4 - p3, v);
  const Vec3 normal = u.cross(v);
  const double denominator = normal.squaredNorm();
  if (std::abs(denominator) <= 2e-13) return out;
  const Vec3 between = p3 - p1;
  // Determinants of the rows (between, v or u, normal).
  const double t = between.dot(u.cross(normal)) / denominator;
  const double s = between.dot(v.cross(normal)) / denominator;
  out.on_second = p3 + t * v;
  out.on_first = p1 + s * u;
  out.s = s / length_u;
  out.t = t / length_v;
  out.found = true;
  return out;
}

/// Where the segment a b crosses the plane n . x + d = 0 (parameters within 1e-5 of [0, 1]);
/// false when the segment is nearly parallel to it (|n . (b - a)| < 1e-5).
inline bool intersect_segment_plane(const Vec3& a, const Vec3& b, const Vec3& n, double d, Vec3& crossing) {
  const Vec3 along = b - a;
  const double rate = along.dot(n);
  if (std::abs(rate) < 1e-5) return false;
  const double t = (-d - n.dot(a)) / rate;
  if (t < -1e-5 || t > 1.0 + 1e-5) return false;
  crossing = a + t * along;
  return true;
}

}  // namespace flatsos::plugin::wrap_math
