#pragma once
// One straight path segment against one wrap surface, in the surface's own frame, with
// OpenSim's semantics (WrapCylinder, WrapSphere, WrapEllipsoid::wrapLine): whether the segment
// wraps (and whether it must), the tangent points r1 (near p1) and r2 (near p2), and the length
// on the surface between them. OpenSim's heuristics and quirks are kept on purpose, so that
// path lengths match OpenSim's; see each function.
// Sources: Delp and Loan, "A computational framework for simulating and analyzing human and
// animal movement", Comput. Sci. Eng. 2000 (the SIMM wrapping these come from); Eberly,
// "Distance from a point to an ellipse/ellipsoid", Graphics Gems IV, 1994.

#include "flatsos/plugin/paths/geometry_path.hpp"

#include <limits>
#include <vector>

namespace flatsos::plugin {

/// OpenSim's WrapObject::WrapAction, with its values.
enum class WrapAction { NoWrap = 0, InsideRadius = 1, Wrapped = 2, MandatoryWrap = 3 };

struct WrapLineResult {
  WrapAction action = WrapAction::NoWrap;
  Eigen::Vector3d r1 = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  Eigen::Vector3d r2 = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  double surface_length_m = 0.0;  ///< from r1 to r2 on the surface (when it wraps)
  /// A candidate (Wrapped) or a must (MandatoryWrap): the path goes p1, r1, surface, r2, p2.
  bool wraps() const { return action == WrapAction::Wrapped || action == WrapAction::MandatoryWrap; }
};

/// A cylinder of `radius_m` around the z axis, `length_m` long (centred on z = 0). OpenSim's
/// closed form: the 2D tangents slid along z onto the plane through p1, p2 and the apex line,
/// a helix between them; unless skip_tangent_adjustment (OpenSim 4 skips it on a path with one
/// wrap) and for a helix of 4 mm or more, the tangent points are then moved until the entering and leaving lines meet
/// the helix within 0.1 deg. No wrap when both tangent points lie beyond the cylinder's ends.
WrapLineResult wrap_cylinder_line(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double radius_m, double length_m,
                                  WrapQuadrant quadrant, bool skip_tangent_adjustment, std::vector<Eigen::Vector3d>* surface_points = nullptr);

/// A sphere of `radius_m` at the origin: the shortest great-circle arc, `Wrapped` (never
/// mandatory) when unconstrained. OpenSim's far-side length is negative, -R (2 pi - angle);
/// that is kept. When the segment passes within 1e-5 (sine) of the centre OpenSim reuses the
/// previous state's tangent points (which it has lost, giving NaN); here the plane holding the
/// segment and the frame axis most perpendicular to it is used instead.
WrapLineResult wrap_sphere_line(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double radius_m, WrapQuadrant quadrant,
                                std::vector<Eigen::Vector3d>* surface_points = nullptr);

/// An ellipsoid with semi-axes `dimensions_m` along x, y, z: wraps only when the segment
/// crosses it, then always `MandatoryWrap`. The wrapping plane through p1, p2 and a surface
/// point c1 found by `method` (OpenSim's hybrid fan/axial blend, midpoint or axial), tangent
/// points by OpenSim's damped Gauss-Newton in that plane, and the length of OpenSim's polyline
/// on the surface (chords of about 1 mm, at most 499).
WrapLineResult wrap_ellipsoid_line(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, const Eigen::Vector3d& dimensions_m,
                                   WrapQuadrant quadrant, WrapMethod method,
                                   std::vector<Eigen::Vector3d>* surface_points = nullptr);

/// The segment p1 p2 given in the wrap object's BODY frame against the object: mapped into the
/// object's frame, wrapped, and r1, r2 (and surface points) mapped back into the body frame.
/// Throws OpenSimModelError naming the object for a WrapTorus or an unsupported wrap type.
WrapLineResult wrap_segment(const OpenSimWrapObject& object, const Eigen::Vector3d& p1_in_body, const Eigen::Vector3d& p2_in_body,
                            WrapMethod method, bool skip_tangent_adjustment, std::vector<Eigen::Vector3d>* surface_points = nullptr);

}  // namespace flatsos::plugin
