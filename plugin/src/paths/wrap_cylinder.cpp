// A path segment over a cylinder, as OpenSim's WrapCylinder::wrapLine computes it (which is
// SIMM's: Delp and Loan 2000): 2D tangent points, slid along the axis onto the plane through the
// segment and the cylinder's apex line, joined by a helix. Kept as OpenSim has it: a helix
// angle of 2 pi - theta for a "long" wrap (2 pi + |theta| when theta < 0), the finite length
// acting only through the tangent points, a constrained cylinder wrapping even without contact
// when neither end is on its side, and the tangency fix-up only for paths with several wraps.

#include <algorithm>
#include <cmath>

#include "flatsos/plugin/paths/wrap_surfaces.hpp"
#include "wrap_math.hpp"

namespace flatsos::plugin {

namespace {

using namespace wrap_math;

const Vec3 kAxisPoint(0.0, 0.0, -1.0);
const Vec3 kAxis(0.0, 0.0, 1.0);
constexpr double kTangencyThreshold_rad = 0.1 * kPi / 180.0;
constexpr int kMaxTangencyIterations = 100;
constexpr double kHelixStep_m = 0.002;

// The two lines from p that touch the circle of radius R around the axis (in p's plane normal
// to the axis): their tangent points, the axis point level with p and p's distance from it.
struct Tangents {
  Vec3 a, b, axis_point;
  double distance = 0.0;
};
Tangents tangents_from(const Vec3& p, double radius) {
  Tangents out;
  out.axis_point = closest_point_on_line(p, kAxisPoint, kAxis);
  Vec3 outward;
  out.distance = normalize_or_zero(p - out.axis_point, outward);
  const double foot = radius * (radius / out.distance);
  const Vec3 base = out.axis_point + foot * outward;
  const double half_chord = std::sqrt(radius * radius - foot * foot);
  const Vec3 across = kAxis.cross(outward);
  out.a = base + half_chord * across;
  out.b = base - half_chord * across;
  return out;
}

struct TangentChoice {
  Vec3 r1, r2;
  bool far_side = false;   // place the apex on the far side of the axis
  bool long_wrap = false;  // the helix goes the long way round
};

// Unconstrained: the pair whose radial directions agree most (the shortest way round).
TangentChoice choose_shortest(const Tangents& t1, const Tangents& t2) {
  const Vec3 a1 = unit_or_zero(t1.a - t1.axis_point), b1 = unit_or_zero(t1.b - t1.axis_point);
  const Vec3 a2 = unit_or_zero(t2.a - t2.axis_point), b2 = unit_or_zero(t2.b - t2.axis_point);
  const double aa = a1.dot(a2), ab = a1.dot(b2), ba = b1.dot(a2), bb = b1.dot(b2);
  TangentChoice c;
  if (aa > ab && aa > ba && aa > bb) {
    c.r1 = t1.a, c.r2 = t2.a;
  } else if (ab > ba && ab > bb) {
    c.r1 = t1.a, c.r2 = t2.b;
  } else if (ba > bb) {
    c.r1 = t1.b, c.r2 = t2.a;
  } else {
    c.r1 = t1.b, c.r2 = t2.b;
  }
  return c;
}

// Constrained: OpenSim's case table on which candidates lie on the active side; alpha and beta
// are the angles between the cross-paired radial vectors.
TangentChoice choose_on_side(const Tangents& t1, const Tangents& t2, const Vec3& p1, const Vec3& p2, WrapQuadrant q) {
  const Vec3 a1 = t1.a - t1.axis_point, b1 = t1.b - t1.axis_point;
  const Vec3 a2 = t2.a - t2.axis_point, b2 = t2.b - t2.axis_point;
  const double alpha = std::acos(a1.dot(b2) / (a1.norm() * b2.norm()));
  const double beta = std::acos(b1.dot(a2) / (b1.norm() * a2.norm()));
  const bool a1_on = sign_of(t1.a[q.axis]) == q.sign, b1_on = sign_of(t1.b[q.axis]) == q.sign;
  const bool a2_on = sign_of(t2.a[q.axis]) == q.sign, b2_on = sign_of(t2.b[q.axis]) == q.sign;
  TangentChoice c;
  auto pick_a_b = [&](bool far) { c.r1 = t1.a, c.r2 = t2.b, c.far_side = far; };
  auto pick_b_a = [&](bool far) { c.r1 = t1.b, c.r2 = t2.a, c.far_side = far; };
  if (a1_on && b1_on) {
    if (a2_on)
      pick_b_a(!(alpha > beta));
    else
      pick_a_b(alpha > beta);
  } else if (a1_on) {
    pick_a_b(alpha > beta);
  } else if (b1_on) {
    pick_b_a(!(alpha > beta));
  } else if (a2_on) {
    pick_b_a(!(alpha > beta));
  } else if (b2_on) {
    pick_a_b(alpha > beta);
  } else if (alpha > beta) {  // no candidate on the active side
    pick_a_b(true);
  } else {
    pick_b_a(true);
  }
  const Vec3 towards_path = (c.r1 - p1) + (c.r2 - p2);
  const Vec3 outwards = (c.r1 - t1.axis_point) + (c.r2 - t2.axis_point);
  c.long_wrap = outwards.dot(towards_path) < 0.0;
  return c;
}

// Slides r1 and r2 along the axis onto the plane through p1, p2 and the apex line (the axis
// point level with the segment's radius-weighted point, pushed out by the radius).
void slide_to_apex_plane(const Vec3& p1, const Vec3& p2, const Tangents& t1, const Tangents& t2, double radius, TangentChoice& c) {
  const double t = t1.distance / (t1.distance + t2.distance);
  const Vec3 mid = p1 + t * (p2 - p1);
  const Vec3 axis_point = closest_point_on_line(mid, kAxisPoint, kAxis);
  const Vec3 l1 = unit_or_zero(p1 - axis_point), l2 = unit_or_zero(p2 - axis_point);
  const Vec3 cross12 = l1.cross(l2);
  const Vec3 normal = unit_or_zero(Vec3(cross12 / cross12.norm()));
  const Vec3 apex1 = axis_point + radius * unit_or_zero(kAxis.cross(normal));
  const Vec3 apex2 = axis_point + radius * unit_or_zero(normal.cross(kAxis));
  const bool first_nearer = (mid - apex1).squaredNorm() < (mid - apex2).squaredNorm();
  const Vec3& apex = first_nearer != c.far_side ? apex1 : apex2;

  const Vec3 cross_apex = unit_or_zero(p1 - apex).cross(unit_or_zero(p2 - apex));
  const Vec3 plane = cross_apex / cross_apex.norm();
  const double offset = -p1.dot(plane);
  const Vec3& p11 = t1.axis_point;
  const Vec3& p22 = t2.axis_point;
  Vec3 crossing;
  // OpenSim measures along the line through p11 with direction p22 (the axis, as both lie on it).
  if (intersect_segment_plane(c.r1 - 10.0 * kAxis, c.r1 + 10.0 * kAxis, plane, offset, crossing)) {
    const Vec3 on_axis = closest_point_on_line(crossing, p11, p22);
    if ((on_axis - p22).squaredNorm() < (p11 - p22).squaredNorm()) c.r1 = crossing;
  }
  if (intersect_segment_plane(c.r2 - 10.0 * kAxis, c.r2 + 10.0 * kAxis, plane, offset, crossing)) {
    const Vec3 on_axis = closest_point_on_line(crossing, p11, p22);
    if ((on_axis - p11).squaredNorm() < (p22 - p11).squaredNorm()) c.r2 = crossing;
  }
}

// Moves r along the axis when the line from p meets the helix (towards `next`, a helix point)
// at more than 0.1 deg of axial slope: 1.5 times the step to where line p-next crosses r's
// generator. Parallel lines (no crossing): r stays.
bool adjust_tangent_point(const Vec3& p, const Vec3& next, Vec3& r) {
  const double slope_in = std::acos(unit_or_zero(r - p).dot(kAxis));
  const double slope_out = std::acos(unit_or_zero(next - r).dot(kAxis));
  if (!(std::abs(slope_in - slope_out) > kTangencyThreshold_rad)) return false;
  const Vec3 p_on_generator = closest_point_on_line(p, r, kAxis);
  const Vec3 next_on_generator = closest_point_on_line(next, r, kAxis);
  const LineIntersection x = intersect_lines(p, next, p_on_generator, next_on_generator);
  if (!x.found) return false;
  r += 1.5 * (x.on_second - r);
  return true;
}

// The helix from r1 to r2 and its length, with the tangency fix-up unless skipped (OpenSim 4
// skips it on a path with one wrap, OpenSim 2.x never did) and for helices shorter than 2 steps.
double helix_length(const Vec3& p1, const Vec3& p2, double radius, bool long_wrap, bool skip_tangent_adjustment, Vec3& r1, Vec3& r2,
                    std::vector<Vec3>* surface_points) {
  const double sense = long_wrap ? -1.0 : 1.0;
  for (int iterations = 0;;) {
    const Vec3 u = r1 - closest_point_on_line(r1, kAxisPoint, kAxis);
    const Vec3 v = r2 - closest_point_on_line(r2, kAxisPoint, kAxis);
    const double axial = (closest_point_on_line(r2, kAxisPoint, kAxis) - closest_point_on_line(r1, kAxisPoint, kAxis)).dot(kAxis);
    double theta = std::atan2(u.cross(v).dot(kAxis), u.dot(v));
    if (long_wrap) theta = 2.0 * kPi - theta;
    const double x = radius * theta;
    const double length = std::sqrt(x * x + axial * axial);
    auto point_at = [&](double t) {  // reads r1 as it is now
      const double angle = sense * t * theta;
      return Vec3(std::cos(angle) * r1.x() - std::sin(angle) * r1.y(), std::sin(angle) * r1.x() + std::cos(angle) * r1.y(),
                  r1.z() + t * axial);
    };
    const int segments = std::max(1, static_cast<int>(length / kHelixStep_m));
    if (!skip_tangent_adjustment && segments >= 2 && iterations < kMaxTangencyIterations) {
      const double t = 1.0 / segments;
      const bool moved1 = adjust_tangent_point(p1, point_at(t), r1);
      const bool moved2 = adjust_tangent_point(p2, point_at(1.0 - t), r2);
      if (moved1 || moved2) {
        ++iterations;
        continue;
      }
    }
    if (surface_points) {
      surface_points->clear();
      for (int i = 0; i <= segments; ++i) surface_points->push_back(point_at(static_cast<double>(i) / segments));
    }
    return length;
  }
}

// Does the segment cross the cylinder? Closest approach of the segment's line to the axis
// within R, at a parameter inside (0, 1).
bool segment_crosses(const LineIntersection& x, double radius) {
  return (x.on_first - x.on_second).squaredNorm() < radius * radius && x.s > 0.0 && x.s < 1.0;
}

}  // namespace

WrapLineResult wrap_cylinder_line(const Vec3& p1, const Vec3& p2, double radius_m, double length_m, WrapQuadrant quadrant,
                                  bool skip_tangent_adjustment, std::vector<Vec3>* surface_points) {
  WrapLineResult out;
  const double r2 = radius_m * radius_m;
  if (distance_squared_to_line(p1, kAxisPoint, kAxis) < r2 || distance_squared_to_line(p2, kAxisPoint, kAxis) < r2) {
    out.action = WrapAction::InsideRadius;
    return out;
  }
  const LineIntersection closest = intersect_lines(p1, p2, Vec3(0.0, 0.0, -0.5 * length_m), Vec3(0.0, 0.0, 0.5 * length_m));
  const bool constrained = quadrant.sign != 0;
  WrapAction action = WrapAction::Wrapped;
  if (!constrained) {
    if (!segment_crosses(closest, radius_m)) return out;
    action = WrapAction::MandatoryWrap;
  } else if (sign_of(p1[quadrant.axis]) == quadrant.sign || sign_of(p2[quadrant.axis]) == quadrant.sign) {
    if (segment_crosses(closest, radius_m))
      action = WrapAction::MandatoryWrap;
    else if (!(sign_of(p1[quadrant.axis]) != sign_of(p2[quadrant.axis]) &&
               sign_of(closest.on_first[quadrant.axis]) != quadrant.sign))
      return out;
  }
  const Tangents t1 = tangents_from(p1, radius_m), t2 = tangents_from(p2, radius_m);
  TangentChoice choice = constrained ? choose_on_side(t1, t2, p1, p2, quadrant) : choose_shortest(t1, t2);
  slide_to_apex_plane(p1, p2, t1, t2, radius_m, choice);
  const double half_length = 0.5 * length_m;
  const auto beyond_ends = [half_length](const Vec3& r) { return r.z() < -half_length || r.z() > half_length; };
  if (beyond_ends(choice.r1) && beyond_ends(choice.r2)) return out;
  out.surface_length_m = helix_length(p1, p2, radius_m, choice.long_wrap, skip_tangent_adjustment, choice.r1, choice.r2, surface_points);
  out.r1 = choice.r1;
  out.r2 = choice.r2;
  out.action = action;
  return out;
}

}  // namespace flatsos::plugin
