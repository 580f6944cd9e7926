#pragma once
// The evaluator's per-evaluation state (private to plugin/src/paths): body poses, the path's
// nodes as OpenSim's GeometryPath builds its current path, and the wrap passes' bookkeeping.

#include <array>
#include <vector>

#include "flatsos/plugin/paths/path_evaluation.hpp"
#include "flatsos/plugin/paths/wrap_surfaces.hpp"

namespace flatsos::plugin {

struct GeometryPathEvaluator::Node {
  int body = 0;  // index into bodies_
  Eigen::Vector3d local = Eigen::Vector3d::Zero(), ground = Eigen::Vector3d::Zero();
  int point = -1, wrap = -1, object = -1;  // path point, PathWrap, wrap object (or -1)
  bool second = false;                     // the tangent point r2
  double surface_length = 0.0;             // on r2
  Eigen::Vector3d moving_rate_local = Eigen::Vector3d::Zero();  // a MovingPathPoint's dP/dq in its body
};

struct GeometryPathEvaluator::Workspace {
  std::vector<Eigen::Isometry3d> poses;  // per body of bodies_
  std::vector<Node> path;
  std::vector<int> order;
  std::vector<WrapAction> results;
  std::vector<std::vector<Eigen::Vector3d>> surfaces;  // per PathWrap, in its body (drawing only)
  std::vector<Eigen::Vector3d> scratch;
  // OpenSim caches a point's location in ground once per state (Point::getLocationInGround,
  // Stage::Position) and moving a tangent point (PathWrapPoint::setLocation) does not clear it:
  // where OpenSim asks for a tangent point's ground location (lengths, length changes, force
  // directions) it gets the one it first saw in this evaluation. Per PathWrap, r1 and r2.
  std::vector<std::array<Eigen::Vector3d, 2>> seen;
  std::vector<std::array<bool, 2>> seen_set;
  double length = 0.0;

  const Eigen::Vector3d& ground_as_seen(const Node& n) {
    if (n.wrap < 0) return n.ground;
    const int which = n.second ? 1 : 0;
    if (!seen_set[n.wrap][which]) seen[n.wrap][which] = n.ground, seen_set[n.wrap][which] = true;
    return seen[n.wrap][which];
  }
  /// Sum of chords, with a same-object tangent pair counting the surface length stored on its
  /// second point (OpenSim's calcLengthAfterPathComputation).
  double path_length() {
    double out = 0.0;
    for (std::size_t i = 1; i < path.size(); ++i) {
      const Node& a = path[i - 1];
      const Node& b = path[i];
      if (a.object >= 0 && a.object == b.object)
        out += b.surface_length;
      else
        out += (ground_as_seen(b) - ground_as_seen(a)).norm();
    }
    return out;
  }
};

// A coordinate's value, 0 where the map does not give it.
inline double value_of(const OpenSimCoordinateValues& q, const std::string& name) {
  const auto it = q.find(name);
  return it == q.end() ? 0.0 : it->second;
}

}  // namespace flatsos::plugin
