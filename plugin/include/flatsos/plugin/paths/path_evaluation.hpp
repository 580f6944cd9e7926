#pragma once
// An OpenSim GeometryPath evaluated for given coordinate values, as OpenSim's GeometryPath does
// it: the active points (ConditionalPathPoints within their range +- 1e-5, MovingPathPoints at
// the coordinate clamped to its range), the PathWraps applied in order (one pass, or up to 8
// passes until the length changes by less than 0.5 mm when there are several, the first
// mandatory segment winning, else the candidate that lengthens the path least), and the length
// with the surface lengths between tangent points. Moment arms are OpenSim's (MomentArmSolver):
// -dL/dq with every point, tangent points included, held in its body, over the segments that
// join different bodies, through coordinate couplers; lengthening speed likewise.
// Body poses come from opensim_body_in_ground (opensim_kinematics.hpp).

#include <string>
#include <vector>

#include "flatsos/plugin/io/opensim_kinematics.hpp"
#include "flatsos/plugin/paths/geometry_path.hpp"
#include "flatsos/plugin/paths/wrap_surfaces.hpp"

namespace flatsos::plugin {

/// One point of an evaluated path, in ground.
struct EvaluatedPathPoint {
  Eigen::Vector3d ground_m = Eigen::Vector3d::Zero();
  std::string body;
  int path_point = -1;  ///< index into OpenSimGeometryPath::points, or -1 for a tangent point
  int path_wrap = -1;   ///< index into OpenSimGeometryPath::wraps of a tangent point
  bool leaves_surface = false;    ///< a tangent point r2 (the path leaves the surface here)
  double surface_length_m = 0.0;  ///< on r2: the length on the surface since r1
  /// On r2, for drawing: the surface path from r1 to r2 (in ground), when asked for.
  std::vector<Eigen::Vector3d> surface_ground_m;
};

struct PathEvaluation {
  double length_m = 0.0;
  std::vector<EvaluatedPathPoint> points;  ///< in path order, tangent points included
};

class GeometryPathEvaluator {
 public:
  /// Throws OpenSimModelError naming the muscle and the point, wrap or body for: a muscle
  /// without a path, a body the model does not have, a coordinate of a conditional or moving
  /// point the model does not have, a moving point's function flatsos does not evaluate, a
  /// wrap object that is not a cylinder, sphere or ellipsoid (WrapTorus is not evaluated).
  GeometryPathEvaluator(const OpenSimModel& model, const OpenSimGeometryPaths& paths, const std::string& muscle);

  const std::string& muscle() const { return path_.muscle; }
  const OpenSimGeometryPath& path() const { return path_; }
  /// The coordinates the length can depend on: those of the joints between ground and the
  /// path's bodies, of conditional and moving points, and the independent coordinates of
  /// couplers driving any of them (model order).
  std::vector<std::string> coordinates() const;

  /// The path's length (m) at q (coordinates not listed are 0).
  double length(const OpenSimCoordinateValues& q) const;
  /// The length and the path's points (tangent points included); `surfaces` adds the surface
  /// paths between tangent points, for drawing.
  PathEvaluation evaluate(const OpenSimCoordinateValues& q, bool surfaces = false) const;
  /// OpenSim's moment arm about `coordinate` (m or dimensionless): -dL/dq with the path's
  /// points fixed in their bodies, plus a coupler's dependent coordinates moving with it.
  /// Throws OpenSimModelError for a coordinate the model does not have.
  double momentArm(const OpenSimCoordinateValues& q, const std::string& coordinate) const;
  /// dL/dt (m/s) for coordinate speeds qdot (those not listed are 0), as OpenSim sums the
  /// speeds between consecutive points.
  double lengtheningSpeed(const OpenSimCoordinateValues& q, const OpenSimCoordinateValues& qdot) const;
  /// The length at q of the path as built at q_path: its points, tangent points included, held
  /// in their bodies (moving points moving with their coordinate), the surface lengths kept.
  /// For a path whose tangent points OpenSim sees where they are (see path_workspace.hpp; all
  /// paths with one PathWrap, unless opensim_2_wrapping), momentArm(q_path, c) is minus its derivative in c at q_path.
  double lengthWithPathHeld(const OpenSimCoordinateValues& q_path, const OpenSimCoordinateValues& q) const;

 private:
  struct Node;       // a path point or tangent point while the path is built
  struct Workspace;  // the nodes and body poses of one evaluation
  struct WrapInfo {
    const OpenSimWrapObject* object = nullptr;
    int object_index = -1, body = -1;
  };
  const OpenSimModel& model_;
  OpenSimGeometryPath path_;
  bool opensim_2_wrapping_ = false;  // OpenSimGeometryPaths::opensim_2_wrapping
  std::vector<std::string> bodies_;               // the path's bodies, wrap bodies and their ancestors
  std::vector<std::vector<const OpenSimJoint*>> chains_;  // per body: joints from it up to ground
  std::vector<int> point_body_;
  std::vector<WrapInfo> wraps_;

  int body_index(const std::string& body, const std::string& where);
  Eigen::Vector3d point_location(int i, const OpenSimCoordinateValues& q, Eigen::Vector3d* rate) const;
  void body_poses(const OpenSimCoordinateValues& q, std::vector<Eigen::Isometry3d>& poses) const;
  void compute(const OpenSimCoordinateValues& q, Workspace& w, bool surfaces) const;
  bool add_active_points(const OpenSimCoordinateValues& q, Workspace& w) const;
  void apply_wraps(Workspace& w, bool surfaces) const;
  bool apply_one_wrap(int k, Workspace& w, bool surfaces, WrapAction& last_result) const;
  double rate_along_path(const OpenSimCoordinateValues& q, Workspace& w, const std::string& coordinate, bool all_segments) const;
};

}  // namespace flatsos::plugin
