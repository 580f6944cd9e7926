// OpenSim's wrap surfaces one segment at a time, against closed forms: a segment crossing a
// cylinder or sphere in a plane normal to its axis wraps by two tangent lines and an arc; with
// an axial offset the tangent-corrected helix approaches the cylinder's geodesic (the unrolled
// straight line); an ellipsoid with equal radii is that sphere (up to OpenSim's 1 mm polyline);
// OpenSim's own quarter-ellipse check (Ramanujan's perimeter); the active-side rules; onset
// continuity; tangency of the entering line; and the insideRadius / noWrap outcomes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "flatsos/plugin/io/opensim_model.hpp"
#include "flatsos/plugin/paths/wrap_surfaces.hpp"

namespace fp = flatsos::plugin;
using Eigen::Vector3d;

namespace {

constexpr double kPi = 3.14159265358979323846;
const fp::WrapQuadrant kAll{};

// P1 = (-a, b), P2 = (a, b) around a circle of radius R at the origin, the path over the +y
// side: two tangent lines of sqrt(d^2 - R^2) and the arc between the tangent points.
struct PlanarWrap {
  double tangent_m, arc_m;
  double total() const { return 2.0 * tangent_m + arc_m; }
};
PlanarWrap over_top(double a, double b, double R) {
  const double d = std::hypot(a, b);
  const double theta = kPi - 2.0 * std::atan2(b, a) - 2.0 * std::acos(R / d);
  return {std::sqrt(d * d - R * R), R * theta};
}

double path_length(const Vector3d& p1, const Vector3d& p2, const fp::WrapLineResult& r) {
  return (r.r1 - p1).norm() + r.surface_length_m + (p2 - r.r2).norm();
}

TEST(WrapCylinder, CrossingSegmentWrapsByTangentsAndArc) {
  const double R = 0.016, a = 0.05, b = 0.006;
  const Vector3d p1(-a, b, 0.0), p2(a, b, 0.0);
  const fp::WrapLineResult r = fp::wrap_cylinder_line(p1, p2, R, 0.05, kAll, true);
  ASSERT_EQ(r.action, fp::WrapAction::MandatoryWrap);
  const PlanarWrap expected = over_top(a, b, R);
  EXPECT_NEAR(r.surface_length_m, expected.arc_m, 1e-12);
  EXPECT_NEAR(path_length(p1, p2, r), expected.total(), 1e-12);
  // On the surface, symmetric, and the entering line tangent (normal to the radius).
  EXPECT_NEAR(std::hypot(r.r1.x(), r.r1.y()), R, 1e-12);
  EXPECT_NEAR(r.r1.x(), -r.r2.x(), 1e-12);
  EXPECT_NEAR(r.r1.y(), r.r2.y(), 1e-12);
  EXPECT_NEAR((r.r1 - p1).dot(Vector3d(r.r1.x(), r.r1.y(), 0.0)), 0.0, 1e-12);
  EXPECT_GT(r.r1.y(), 0.0);  // the short way: over the top
}

TEST(WrapCylinder, HelixWithTangencyFixUpApproachesTheGeodesic) {
  const double R = 0.01, a = 0.04, b = 0.004, dz = 0.03;
  const Vector3d p1(-a, b, -0.5 * dz), p2(a, b, 0.5 * dz);
  const PlanarWrap planar = over_top(a, b, R);
  const double geodesic = std::hypot(planar.total(), dz);  // the unrolled straight line
  const fp::WrapLineResult fixed = fp::wrap_cylinder_line(p1, p2, R, 0.1, kAll, false);
  ASSERT_TRUE(fixed.wraps());
  // Tangency to 0.1 deg leaves an error of second order in that angle.
  const double angle_rad = 0.1 * kPi / 180.0;
  EXPECT_NEAR(path_length(p1, p2, fixed), geodesic, geodesic * angle_rad * angle_rad);
  EXPECT_GE(path_length(p1, p2, fixed), geodesic - 1e-12);  // the geodesic is the shortest
  // The entering line meets the helix at its slope: the helix rises dz over the unrolled length.
  const Vector3d entering = (fixed.r1 - p1).normalized();
  const double helix_slope = dz / planar.total();
  EXPECT_NEAR(entering.z() / std::hypot(entering.x(), entering.y()), helix_slope, 2.0 * angle_rad * (1.0 + helix_slope * helix_slope));
  // A single wrap keeps OpenSim's closed-form tangent points: longer than the geodesic, but
  // within the slide's approximation.
  const fp::WrapLineResult single = fp::wrap_cylinder_line(p1, p2, R, 0.1, kAll, true);
  EXPECT_GE(path_length(p1, p2, single), geodesic - 1e-12);
  EXPECT_LT(path_length(p1, p2, single) - geodesic, 1e-3 * geodesic);
}

TEST(WrapCylinder, ConstrainedSideWrapsTheLongWayEvenWithoutContact) {
  const double R = 0.01, a = 0.05;
  const fp::WrapQuadrant plus_y{1, 1};
  for (double b : {-0.005, -0.02}) {  // crossing, and missing the cylinder entirely
    const Vector3d p1(-a, b, 0.0), p2(a, b, 0.0);
    const fp::WrapLineResult r = fp::wrap_cylinder_line(p1, p2, R, 0.05, plus_y, true);
    ASSERT_EQ(r.action, fp::WrapAction::Wrapped) << b;  // both ends off the active side
    EXPECT_GT(r.r1.y(), 0.0);
    EXPECT_NEAR(path_length(p1, p2, r), over_top(a, b, R).total(), 1e-12) << b;
  }
  // Unconstrained, the missing segment does not wrap.
  EXPECT_EQ(fp::wrap_cylinder_line({-a, -0.02, 0.0}, {a, -0.02, 0.0}, R, 0.05, kAll, true).action, fp::WrapAction::NoWrap);
}

TEST(WrapCylinder, FiniteLengthActsThroughTheTangentPointsOnly) {
  const double R = 0.01, a = 0.04, b = 0.004;
  // Tangent points beyond both ends: no wrap, although the line crosses the infinite cylinder.
  EXPECT_EQ(fp::wrap_cylinder_line({-a, b, 0.2}, {a, b, 0.2}, R, 0.1, kAll, true).action, fp::WrapAction::NoWrap);
  // Beyond one end only: it still wraps.
  EXPECT_TRUE(fp::wrap_cylinder_line({-a, b, 0.0}, {a, b, 0.1}, R, 0.1, kAll, true).wraps());
}

TEST(WrapCylinder, OnsetIsContinuous) {
  const double R = 0.01, a = 0.05;
  auto extra = [&](double depth) {
    const Vector3d p1(-a, R - depth, 0.0), p2(a, R - depth, 0.0);
    const fp::WrapLineResult r = fp::wrap_cylinder_line(p1, p2, R, 0.05, kAll, true);
    return r.wraps() ? path_length(p1, p2, r) - 2.0 * a : 0.0;
  };
  EXPECT_EQ(extra(-1e-6), 0.0);  // just missing
  // Just touching: less than the arc's excess over its chord, R/3 (2 depth/R)^(3/2).
  for (double depth : {1e-6, 1e-8}) {
    EXPECT_GT(extra(depth), 0.0);
    EXPECT_LT(extra(depth), R / 3.0 * std::pow(2.0 * depth / R, 1.5) + 1e-15) << depth;
  }
}

TEST(WrapCylinder, EndInsideTheRadiusIsReported) {
  EXPECT_EQ(fp::wrap_cylinder_line({0.005, 0.0, 0.0}, {0.05, 0.01, 0.0}, 0.01, 0.05, kAll, true).action,
            fp::WrapAction::InsideRadius);
}

TEST(WrapSphere, CrossingSegmentIsACandidateWithTheGreatCircleArc) {
  const double R = 0.02, a = 0.06, b = 0.008;
  // Tilted out of the xy plane: the sphere has no preferred plane.
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.7, Vector3d(1.0, 2.0, 0.5).normalized()).toRotationMatrix();
  const Vector3d p1 = tilt * Vector3d(-a, b, 0.0), p2 = tilt * Vector3d(a, b, 0.0);
  const fp::WrapLineResult r = fp::wrap_sphere_line(p1, p2, R, kAll);
  ASSERT_EQ(r.action, fp::WrapAction::Wrapped);  // OpenSim lets the path compare segments
  const PlanarWrap expected = over_top(a, b, R);
  EXPECT_NEAR(r.surface_length_m, expected.arc_m, 1e-12);
  EXPECT_NEAR(path_length(p1, p2, r), expected.total(), 1e-12);
  EXPECT_NEAR(r.r1.norm(), R, 1e-12);
  EXPECT_NEAR((r.r2 - p2).dot(r.r2), 0.0, 1e-12);  // tangent at r2
}

TEST(WrapSphere, ConstrainedSideAndOutcomes) {
  const double R = 0.01, a = 0.05, b = -0.005;
  const Vector3d p1(-a, b, 0.0), p2(a, b, 0.0);
  const fp::WrapLineResult r = fp::wrap_sphere_line(p1, p2, R, fp::WrapQuadrant{1, 1});
  ASSERT_EQ(r.action, fp::WrapAction::Wrapped);
  EXPECT_NEAR(path_length(p1, p2, r), over_top(a, b, R).total(), 1e-12);
  // An end on the active side and a crossing segment: mandatory.
  EXPECT_EQ(fp::wrap_sphere_line({-a, 0.004, 0.0}, {a, -0.002, 0.0}, R, fp::WrapQuadrant{1, 1}).action, fp::WrapAction::MandatoryWrap);
  EXPECT_EQ(fp::wrap_sphere_line({-a, 0.02, 0.0}, {a, 0.02, 0.0}, R, kAll).action, fp::WrapAction::NoWrap);
  EXPECT_EQ(fp::wrap_sphere_line({-0.005, 0.0, 0.0}, {a, 0.0, 0.0}, R, kAll).action, fp::WrapAction::InsideRadius);
  // Through the centre: a plane is chosen; every plane gives the same length.
  const fp::WrapLineResult centre = fp::wrap_sphere_line({-a, 0.0, 0.0}, {a, 0.0, 0.0}, R, kAll);
  ASSERT_TRUE(centre.wraps());
  EXPECT_NEAR(path_length({-a, 0.0, 0.0}, {a, 0.0, 0.0}, centre), over_top(a, 0.0, R).total(), 1e-12);
}

// OpenSim's surface path is a polyline: floor(|r1 - r2| / 1 mm) chords (at most 499), each
// short of its arc by s^3 / (24 R^2) for an arc s.
double polyline_shortfall(const fp::WrapLineResult& sphere, double R) {
  const int chords = std::max(1, std::min(499, static_cast<int>((sphere.r1 - sphere.r2).norm() / 0.001)));
  const double s = sphere.surface_length_m / chords;
  return chords * s * s * s / (24.0 * R * R);
}

TEST(WrapEllipsoid, EqualRadiiWrapLikeTheSphere) {
  const double R = 0.02, a = 0.06;
  for (fp::WrapMethod method : {fp::WrapMethod::Hybrid, fp::WrapMethod::Midpoint, fp::WrapMethod::Axial})
    for (double b : {0.004, 0.012}) {
      const Vector3d p1(-a, b, 0.0), p2(a, b, 0.0);  // the wrapping plane holds the centre: equal chords
      const fp::WrapLineResult sphere = fp::wrap_sphere_line(p1, p2, R, kAll);
      const fp::WrapLineResult r = fp::wrap_ellipsoid_line(p1, p2, Vector3d::Constant(R), kAll, method);
      ASSERT_EQ(r.action, fp::WrapAction::MandatoryWrap);
      // OpenSim's tangent search stops at a squared residual of 1e-8 (units where the radii sum
      // to 3): the tangent points within 1e-4 R, at most 0.5e-4 R off the surface; an end moved
      // off the surface by that changes its ~1 mm chord by at most that times the chord's angle.
      EXPECT_NEAR((r.r1 - sphere.r1).norm(), 0.0, 1e-4 * R) << b;
      const double off_surface = 0.5e-4 * R * (0.001 / R);
      EXPECT_NEAR(path_length(p1, p2, r), path_length(p1, p2, sphere), polyline_shortfall(sphere, R) + 2.0 * off_surface) << b;
      EXPECT_LE(r.surface_length_m, sphere.surface_length_m + 1e-8);
    }
}

TEST(WrapEllipsoid, QuarterEllipseMatchesRamanujansPerimeter) {
  // OpenSim's testGeometryPathWrapping: from (r - 0.1, r, 0) over the top of the ellipse with
  // semi-axes A, r and down to (-A, -r, 0): 2 r - 0.1 plus a quarter perimeter.
  const double r = 0.5;
  for (double angle = 0.0; angle < kPi / 2 - 0.1; angle += kPi / 36) {
    const double A = r / std::cos(angle);
    const Vector3d p1(r - 0.1, r, 0.0), p2(-A, -r, 0.0);
    const fp::WrapLineResult w = fp::wrap_ellipsoid_line(p1, p2, Vector3d(A, r, 1.0), kAll, fp::WrapMethod::Hybrid);
    ASSERT_TRUE(w.wraps());
    const double h = (A - r) * (A - r) / ((A + r) * (A + r));
    const double perimeter = kPi * (A + r) * (1.0 + 3.0 * h / (10.0 + std::sqrt(4.0 - 3.0 * h)));
    EXPECT_NEAR(path_length(p1, p2, w), 2.0 * r - 0.1 + perimeter / 4.0, 1e-4) << angle;  // OpenSim's tolerance
  }
}

TEST(WrapEllipsoid, ActiveSideAndOutcomes) {
  const Vector3d dims(0.035, 0.02, 0.02);
  const Vector3d p1(-0.06, 0.0, 0.004), p2(0.06, 0.0, 0.004);
  // The segment passes on the +z side; constrained to -z it must go round underneath.
  const fp::WrapLineResult free = fp::wrap_ellipsoid_line(p1, p2, dims, kAll, fp::WrapMethod::Hybrid);
  const fp::WrapLineResult below = fp::wrap_ellipsoid_line(p1, p2, dims, fp::WrapQuadrant{2, -1}, fp::WrapMethod::Hybrid);
  ASSERT_TRUE(free.wraps() && below.wraps());
  EXPECT_GT(free.r1.z(), 0.0);
  EXPECT_LT(below.r1.z(), 0.0);
  EXPECT_GT(path_length(p1, p2, below), path_length(p1, p2, free));
  // Symmetric in x: symmetric tangent points and both tangent lines in the surface's tangent planes.
  EXPECT_NEAR(free.r1.x(), -free.r2.x(), 1e-6);
  const Vector3d normal = free.r1.cwiseQuotient(dims.cwiseProduct(dims)).normalized();
  EXPECT_NEAR((free.r1 - p1).normalized().dot(normal), 0.0, 1e-3);
  EXPECT_EQ(fp::wrap_ellipsoid_line({-0.06, 0.0, 0.03}, {0.06, 0.0, 0.03}, dims, kAll, fp::WrapMethod::Hybrid).action, fp::WrapAction::NoWrap);
  EXPECT_EQ(fp::wrap_ellipsoid_line({-0.01, 0.0, 0.0}, {0.06, 0.0, 0.0}, dims, kAll, fp::WrapMethod::Hybrid).action,
            fp::WrapAction::InsideRadius);
}

TEST(WrapSegment, WorksInTheObjectsFrameAndMapsBack) {
  fp::OpenSimWrapObject cylinder;
  cylinder.name = "pulley";
  cylinder.type = "WrapCylinder";
  cylinder.surface = fp::OpenSimWrapSurface::Cylinder;
  cylinder.radius_m = 0.016;
  cylinder.length_m = 0.05;
  cylinder.pose_in_body.linear() = Eigen::AngleAxisd(0.4, Vector3d(0.3, -1.0, 0.2).normalized()).toRotationMatrix();
  cylinder.pose_in_body.translation() = Vector3d(0.01, -0.2, 0.03);
  const Vector3d p1 = cylinder.pose_in_body * Vector3d(-0.05, 0.006, 0.0), p2 = cylinder.pose_in_body * Vector3d(0.05, 0.006, 0.0);
  const fp::WrapLineResult r = fp::wrap_segment(cylinder, p1, p2, fp::WrapMethod::Hybrid, true);
  ASSERT_TRUE(r.wraps());
  EXPECT_NEAR(path_length(p1, p2, r), over_top(0.05, 0.006, 0.016).total(), 1e-12);
  EXPECT_NEAR((cylinder.pose_in_body.inverse() * r.r1).head<2>().norm(), 0.016, 1e-12);
  cylinder.surface = fp::OpenSimWrapSurface::Torus;
  EXPECT_THROW(fp::wrap_segment(cylinder, p1, p2, fp::WrapMethod::Hybrid, true), fp::OpenSimModelError);
}

}  // namespace
