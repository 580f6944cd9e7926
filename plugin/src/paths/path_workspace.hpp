#pragma once
// The evaluator's per-evaluation state (private to plugin/src/paths): body poses, the path's
// nodes as OpenSim's GeometryPath builds its current path, and the wrap passes' bookkeeping.

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
  double length = 0.0;
};

/// Sum of chords, with a same-object tangent pair counting the surface length stored on its
/// second point (OpenSim's calcLengthAfterPathComputation).
template <class Nodes>
double path_length(const Nodes& path) {
  double length = 0.0;
  for (std::size_t i = 1; i < path.size(); ++i) {
    const auto& a = path[i - 1];
    const auto& b = path[i];
    if (a.object >= 0 && a.object == b.object)
      length += b.surface_length;
    else
      length += (b.ground - a.ground).norm();
  }
  return length;
}

}  // namespace flatsos::plugin
