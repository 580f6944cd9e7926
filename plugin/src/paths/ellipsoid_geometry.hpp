#pragma once
// The pieces of OpenSim's WrapEllipsoid that are plain geometry, on an ellipsoid centred at the
// origin with semi-axes a (all in OpenSim's scaled units, where a sums to 3): the closest
// surface point to a point (Eberly, Graphics Gems IV, 1994, with OpenSim's 2D special cases),
// a tangent point in a plane (OpenSim's damped Gauss-Newton), and the polyline OpenSim
// measures the wrap length on.

#include "wrap_math.hpp"

#include <vector>

namespace flatsos::plugin::ellipsoid {

using wrap_math::Vec3;

/// The surface point closest to p. special_axis 0, 1 or 2 solves in the plane x_axis = p_axis
/// (2D); -1 picks such a plane when p lies within 2e-13 of coordinate planes (the narrowest
/// cross-section), else solves in 3D (64 Newton steps at most; the last iterate if none meets
/// OpenSim's |f| < 1e-9).
Vec3 closest_point(const Vec3& a, const Vec3& p, int special_axis = -1);

/// Moves r (starting guess, on or near the surface) to where the plane vs . r + vs4 = 0 cuts
/// the surface and the line from p touches it; p_level = sum (p_i / a_i)^2 - 1. OpenSim's
/// iteration as it is (4 residuals, Levenberg damping, at most 50 outer steps); r = p when
/// |p_level| < 1e-4.
void tangent_point(double p_level, const Vec3& p, const Vec3& a, const Vec3& vs, double vs4, Vec3& r);

/// OpenSim's surface path from r1 to r2 in the plane (vs, vs4): rays from the plane's point on
/// the axis most aligned with vs, turned evenly from r1 to r2 (the other way round when
/// far_side), cut with the surface; chords of about 1 mm (`factor` converts to metres), at
/// most 499. A chord under 1 mm is the path itself.
struct Polyline {
  double length = 0.0;  ///< scaled units
  int point_count = 0;  ///< r1, the interior points, r2
  Vec3 first_interior = Vec3::Zero(), last_interior = Vec3::Zero();
};
Polyline surface_polyline(const Vec3& r1, const Vec3& r2, const Vec3& a, const Vec3& vs, double vs4, bool far_side, double factor,
                          std::vector<Vec3>* points);

}  // namespace flatsos::plugin::ellipsoid
