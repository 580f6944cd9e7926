// One path segment against one of a body's wrap objects: into the object's frame, the surface's
// wrapLine, and back (OpenSim's WrapObject::wrapPathSegment).

#include "flatsos/plugin/io/opensim_model.hpp"  // OpenSimModelError
#include "flatsos/plugin/paths/wrap_surfaces.hpp"

namespace flatsos::plugin {

WrapLineResult wrap_segment(const OpenSimWrapObject& object, const Eigen::Vector3d& p1_in_body, const Eigen::Vector3d& p2_in_body,
                            WrapMethod method, bool skip_tangent_adjustment, std::vector<Eigen::Vector3d>* surface_points) {
  const Eigen::Isometry3d body_to_object = object.pose_in_body.inverse();
  const Eigen::Vector3d p1 = body_to_object * p1_in_body, p2 = body_to_object * p2_in_body;
  WrapLineResult out;
  switch (object.surface) {
    case OpenSimWrapSurface::Cylinder:
      out = wrap_cylinder_line(p1, p2, object.radius_m, object.length_m, object.quadrant, skip_tangent_adjustment, surface_points);
      break;
    case OpenSimWrapSurface::Sphere: out = wrap_sphere_line(p1, p2, object.radius_m, object.quadrant, surface_points); break;
    case OpenSimWrapSurface::Ellipsoid:
      out = wrap_ellipsoid_line(p1, p2, object.dimensions_m, object.quadrant, method, surface_points);
      break;
    case OpenSimWrapSurface::Torus:
    case OpenSimWrapSurface::Unsupported:
      throw OpenSimModelError(object.type + " '" + object.name + "': this wrap surface is not evaluated by flatsos "
                              "(WrapCylinder, WrapSphere and WrapEllipsoid are)");
  }
  if (out.wraps()) {
    out.r1 = object.pose_in_body * out.r1;
    out.r2 = object.pose_in_body * out.r2;
    if (surface_points)
      for (Eigen::Vector3d& p : *surface_points) p = object.pose_in_body * p;
  } else if (surface_points) {
    surface_points->clear();
  }
  return out;
}

}  // namespace flatsos::plugin
