#pragma once
// The path seam of simulation: a muscle whose path is evaluated from its geometry (an OpenSim
// GeometryPath with via points and wrapping) instead of its fitted length polynomial. Planning
// always uses the polynomial (smooth, with exact derivatives); a simulation asked for the
// geometry (--paths geometry) uses this, to compare with OpenSim's own simulations.
// The arguments are those of the muscle's polynomial path, in its order (the coordinates it
// depends on); the moment arms are the generalized forces per newton of tension, as OpenSim
// applies a path's tension (for a wrapped path they need not be -dL/dq exactly).

namespace flatsos::plugin {

class PathGeometry {
 public:
  virtual ~PathGeometry() = default;
  /// The musculotendon length (m) at the arguments x.
  virtual double length_m(const double* x) const = 0;
  /// The moment arm about each argument (m; 1 per m for a slider) into out.
  virtual void momentArms(const double* x, double* out) const = 0;
  /// dL/dx_k into out: what moves the tendon when the fibre's length is L - L_S (it differs from
  /// minus the moment arm where the path's tangent points are not those of the shortest path).
  virtual void lengthGradient(const double* x, double* out) const = 0;
};

}  // namespace flatsos::plugin
