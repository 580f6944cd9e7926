// A path segment over a sphere, as OpenSim's WrapSphere::wrapLine computes it (SIMM's: Delp and
// Loan 2000): the tangent lines from each end in the plane through both ends and the centre, the
// pair making the shortest arc (or, when constrained, the pair on the active side), and the arc
// between them. Kept as OpenSim has it: unconstrained wraps are candidates ("Wrapped"), a
// constrained wrap counts its "inside the segment" test in metres along the segment, and the
// far-side arc length is negative.

#include <algorithm>
#include <cmath>

#include "flatsos/plugin/paths/wrap_surfaces.hpp"
#include "wrap_math.hpp"

namespace flatsos::plugin {

namespace {

using namespace wrap_math;

struct SphereTangents {
  Vec3 a, b;
};

// The tangent points of the lines from p in the plane with normal n through the centre:
// unit(-p) turned by -+asin(R / |p|) about n, at the tangent distance from p.
SphereTangents tangents_from(const Vec3& p, const Vec3& n, double radius) {
  const Vec3 inward = unit_or_zero(-p);
  const Vec3 side = n.cross(inward);
  const double angle = std::asin(radius / p.norm());
  const double reach = p.norm() * std::cos(angle);
  SphereTangents out;
  out.a = p + reach * (std::cos(angle) * inward - std::sin(angle) * side);
  out.b = p + reach * (std::cos(angle) * inward + std::sin(angle) * side);
  return out;
}

// The plane's normal: through both ends and the centre; for a segment through the centre, the
// plane holding the frame axis most perpendicular to the segment.
Vec3 plane_normal(const Vec3& along, const Vec3& towards_p2) {
  const Vec3 h = along.cross(towards_p2);
  if (h.norm() >= 1e-5) return unit_or_zero(h);
  Eigen::Index axis = 0;
  along.cwiseAbs().minCoeff(&axis);
  return unit_or_zero(along.cross(Vec3::Unit(axis)));
}

struct ArcChoice {
  Vec3 r1, r2, other1, other2;
  bool far_side = false;
};

// The active-side rules: which candidates, and whether the arc runs round the far side.
void constrain(const Vec3& p1, const Vec3& p2, const SphereTangents& t1, const SphereTangents& t2, WrapQuadrant q, ArcChoice& c) {
  Vec3 axis = Vec3::Zero();
  axis[q.axis] = q.sign;
  const Vec3 to_centre = unit_or_zero(-p1 - p2);
  const Vec3 a1 = unit_or_zero(t1.a), b1 = unit_or_zero(t1.b), a2 = unit_or_zero(t2.a), b2 = unit_or_zero(t2.b);
  const bool first_a = a1.dot(to_centre) > b1.dot(to_centre);
  c.r1 = first_a ? t1.a : t1.b;
  c.other1 = first_a ? t1.b : t1.a;
  const bool second_a = a2.dot(to_centre) > b2.dot(to_centre);
  c.r2 = second_a ? t2.a : t2.b;
  c.other2 = second_a ? t2.b : t2.a;
  if (unit_or_zero((c.r1 - p1) + (c.r2 - p2)).dot(axis) < 0.0) {
    c.r1 = c.other1;
    c.r2 = c.other2;
  }
  const Vec3 towards_path = (c.r1 - p1) + (c.r2 - p2);
  c.far_side = (c.r1 + c.r2).dot(towards_path) < 0.0;
}

// The arc from r1 to r2 (centre at the origin) as points, for drawing.
void arc_points(const Vec3& r1, const Vec3& r2, double angle, std::vector<Vec3>* points) {
  if (!points) return;
  points->clear();
  const Vec3 axis = unit_or_zero(r1.cross(r2));
  const int segments = std::max(1, static_cast<int>(std::abs(angle) * r1.norm() / 0.002));
  for (int i = 0; i <= segments; ++i)
    points->push_back(Eigen::AngleAxisd(angle * i / segments, axis) * r1);
}

}  // namespace

WrapLineResult wrap_sphere_line(const Vec3& p1, const Vec3& p2, double radius_m, WrapQuadrant quadrant,
                                std::vector<Vec3>* surface_points) {
  WrapLineResult out;
  if (p1.norm() < radius_m || p2.norm() < radius_m) {
    out.action = WrapAction::InsideRadius;
    return out;
  }
  // The segment p2 + l (p1 - p2) must enter and leave the sphere between its ends.
  const Vec3 along = p1 - p2;
  const double a = along.dot(along), b = 2.0 * p2.dot(along), c = p2.dot(p2) - radius_m * radius_m;
  const double discriminant = b * b - 4.0 * a * c;
  if (discriminant < 0.0) return out;
  const double l1 = (-b + std::sqrt(discriminant)) / (2.0 * a), l2 = (-b - std::sqrt(discriminant)) / (2.0 * a);
  if (!(0.0 < l1 && l1 < 1.0) || !(0.0 < l2 && l2 < 1.0) || l1 < l2) return out;

  const Vec3 unit_along = unit_or_zero(along);
  const Vec3 n = plane_normal(unit_along, unit_or_zero(p2));
  const bool through_centre = unit_along.cross(unit_or_zero(p2)).norm() < 1e-5;
  const SphereTangents t1 = tangents_from(p1, n, radius_m), t2 = tangents_from(p2, n, radius_m);
  const Vec3 a1 = unit_or_zero(t1.a), b1 = unit_or_zero(t1.b), a2 = unit_or_zero(t2.a), b2 = unit_or_zero(t2.b);
  const double aa = a1.dot(a2), ab = a1.dot(b2), ba = b1.dot(a2), bb = b1.dot(b2);
  ArcChoice choice;
  if (aa > ab && aa > ba && aa > bb)
    choice = {t1.a, t2.a, t1.b, t2.b};
  else if (ab > ba && ab > bb)
    choice = {t1.a, t2.b, t1.b, t2.a};
  else if (ba > bb)
    choice = {t1.b, t2.a, t1.a, t2.b};
  else
    choice = {t1.b, t2.b, t1.a, t2.a};

  WrapAction action = WrapAction::Wrapped;
  if (quadrant.sign != 0 && !through_centre) {
    const int k = quadrant.axis;
    const bool p1_on = sign_of(p1[k]) == quadrant.sign, p2_on = sign_of(p2[k]) == quadrant.sign;
    if (p1_on || p2_on) {
      // OpenSim's "closest point inside the segment" test: 0 < distance along p1 -> p2 < 1 (m).
      const double along_m = -((-p1).dot(unit_along));
      const Vec3 closest = p1 - along_m * unit_along;
      if (closest.squaredNorm() < radius_m * radius_m && along_m > 0.0 && along_m < 1.0)
        action = WrapAction::MandatoryWrap;
      else if (!(sign_of(p1[k]) != sign_of(p2[k]) && sign_of(closest[k]) != quadrant.sign))
        return out;
    }
    if (!p1_on || !p2_on) constrain(p1, p2, t1, t2, quadrant, choice);
  }
  double angle = std::acos(unit_or_zero(choice.r1).dot(unit_or_zero(choice.r2)));
  if (choice.far_side) angle = -(2.0 * kPi - angle);
  out.action = action;
  out.r1 = choice.r1;
  out.r2 = choice.r2;
  out.surface_length_m = radius_m * angle;
  arc_points(choice.r1, choice.r2, angle, surface_points);
  return out;
}

}  // namespace flatsos::plugin
