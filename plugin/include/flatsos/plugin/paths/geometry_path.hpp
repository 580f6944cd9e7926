#pragma once
// OpenSim's muscle paths as an .osim file gives them (GeometryPath): ordered path points, each
// fixed to a body (PathPoint), present only while a coordinate lies in a range
// (ConditionalPathPoint), or moving with a coordinate (MovingPathPoint); the wrap objects
// (WrapCylinder, WrapSphere, WrapEllipsoid, WrapTorus) of every body; and each path's PathWraps.
// Read with Simbody's XML parser, OpenSim 3 and 4 files. Evaluation: path_evaluation.hpp.

#include "flatsos/plugin/ndebug_guard.hpp"           // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "flatsos/plugin/io/opensim_function.hpp"
#include "flatsos/plugin/io/opensim_paths.hpp"  // OpenSimFileError

namespace flatsos::plugin {

enum class OpenSimPathPointKind { Fixed, Conditional, Moving };

struct OpenSimPathPoint {
  std::string name;
  OpenSimPathPointKind kind = OpenSimPathPointKind::Fixed;
  std::string body;  ///< the body its frame is fixed to ("ground" or a body name)
  /// The parent frame in the body (identity unless the point names a PhysicalOffsetFrame).
  Eigen::Isometry3d frame_in_body = Eigen::Isometry3d::Identity();
  Eigen::Vector3d location_m = Eigen::Vector3d::Zero();  ///< in the parent frame (Fixed, Conditional)
  /// Conditional: the coordinate whose range switches the point; Moving: the one coordinate of
  /// x, y and z ("" when none: each location function is then evaluated at 0).
  std::string coordinate;
  std::array<double, 2> active_range{0.0, 0.0};  ///< Conditional, rad or m (OpenSim adds 1e-5 each side)
  std::array<OpenSimFunction, 3> moving_location;  ///< Moving: x, y, z of the coordinate
};

enum class OpenSimWrapSurface { Cylinder, Sphere, Ellipsoid, Torus, Unsupported };

/// The side a wrap object constrains the path to: the sign of one axis of its own frame, or
/// sign 0 for "all" (unconstrained).
struct WrapQuadrant {
  int axis = 0;
  int sign = 0;
};

struct OpenSimWrapObject {
  std::string name, type;  ///< type: the element's tag, e.g. "WrapCylinder"
  OpenSimWrapSurface surface = OpenSimWrapSurface::Unsupported;
  std::string body;  ///< "ground" or a body name
  /// The wrap object's frame in its body: translation, then body-fixed XYZ rotation.
  Eigen::Isometry3d pose_in_body = Eigen::Isometry3d::Identity();
  bool active = true;
  WrapQuadrant quadrant;
  double radius_m = 0.0;  ///< cylinder, sphere
  double length_m = 0.0;  ///< cylinder (along its z axis)
  Eigen::Vector3d dimensions_m = Eigen::Vector3d::Zero();  ///< ellipsoid's semi-axes
  double inner_radius_m = 0.0, outer_radius_m = 0.0;        ///< torus
};

/// How an ellipsoid finds its wrapping plane (the other surfaces ignore it).
enum class WrapMethod { Hybrid, Midpoint, Axial };

struct OpenSimPathWrap {
  std::string name;
  std::string wrap_object;
  WrapMethod method = WrapMethod::Hybrid;
  /// 1-based indices into the path's points (inactive conditional points count); a value < 1
  /// means the first (start) or the last (end) point.
  std::array<int, 2> range{-1, -1};
};

struct OpenSimGeometryPath {
  std::string muscle;  ///< the force that owns the path
  std::vector<OpenSimPathPoint> points;
  std::vector<OpenSimPathWrap> wraps;
};

struct OpenSimGeometryPaths {
  std::vector<OpenSimWrapObject> wrap_objects;
  std::vector<OpenSimGeometryPath> paths;  ///< ForceSet order
  /// Wrap as OpenSim 2.x did: the tangent points on a cylinder adjusted also on a path with one
  /// wrap (OpenSim 4 adjusts them only when the path has several; on arm26's BRA the lengths
  /// differ by up to 0.02 mm). Not in the file: the importer sets it with opensim_2_muscles.
  bool opensim_2_wrapping = false;

  const OpenSimGeometryPath* path(const std::string& muscle) const;
  const OpenSimWrapObject* wrapObject(const std::string& name) const;
};

/// Reads every wrap object and every ForceSet member's GeometryPath of an .osim document.
/// Throws OpenSimFileError naming the file, the muscle, the point or wrap object and the field
/// for: a document without a Model, a point whose frame is neither ground, a body nor a
/// PhysicalOffsetFrame on one, a number that does not parse, a ConditionalPathPoint without a
/// coordinate or range, a MovingPathPoint whose x, y and z use different coordinates or whose
/// function is missing, a PathWrap naming an unknown wrap object or method or a range outside
/// the path, a quadrant OpenSim refuses, a negative radius or length, ellipsoid or torus radii
/// <= 0, and two wrap objects or paths of the same name.
OpenSimGeometryPaths parse_opensim_geometry_paths(const std::string& xml, const std::string& source);
/// The same from a file.
OpenSimGeometryPaths read_opensim_geometry_paths(const std::string& file);

}  // namespace flatsos::plugin
