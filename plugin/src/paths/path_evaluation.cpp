// GeometryPath evaluation in OpenSim's order (GeometryPath::computePath, applyWrapObjects,
// calcLengthAfterPathComputation): see path_evaluation.hpp. Wrap passes follow OpenSim to the
// letter, including its early exit when a wrap's range holds no active point and the swap of
// the first two wraps after a first pass that found noWrap then insideRadius.

#include <algorithm>
#include <cmath>
#include <limits>

#include "path_workspace.hpp"

namespace flatsos::plugin {

namespace {

// The workspace of this thread: evaluations reuse its storage instead of allocating.
template <class Workspace>
Workspace& thread_workspace() {
  thread_local Workspace w;
  return w;
}

}  // namespace

int GeometryPathEvaluator::body_index(const std::string& body, const std::string& where) {
  const auto found = std::find(bodies_.begin(), bodies_.end(), body);
  if (found != bodies_.end()) return static_cast<int>(found - bodies_.begin());
  if (body != "ground" && !model_.body(body)) throw OpenSimModelError(where + ": the model has no body '" + body + "'");
  bodies_.push_back(body);
  chains_.emplace_back();
  const int index = static_cast<int>(bodies_.size()) - 1;
  std::string current = body;
  while (current != "ground") {
    const OpenSimJoint* joint = model_.jointOfChild(current);
    if (!joint || chains_[index].size() > model_.joints.size())
      throw OpenSimModelError(where + ": body '" + current + "' is not connected to ground by joints");
    chains_[index].push_back(joint);
    current = joint->parent_body;
  }
  for (const OpenSimJoint* joint : std::vector<const OpenSimJoint*>(chains_[index])) body_index(joint->parent_body, where);
  return index;
}

GeometryPathEvaluator::GeometryPathEvaluator(const OpenSimModel& model, const OpenSimGeometryPaths& paths, const std::string& muscle)
    : model_(model) {
  const OpenSimGeometryPath* path = paths.path(muscle);
  if (!path) throw OpenSimModelError("'" + muscle + "': no force of this name has a GeometryPath");
  path_ = *path;
  opensim_2_wrapping_ = paths.opensim_2_wrapping;
  for (const OpenSimPathPoint& p : path_.points) {
    const std::string where = muscle + ": point '" + p.name + "'";
    point_body_.push_back(body_index(p.body, where));
    if (p.kind != OpenSimPathPointKind::Fixed && !p.coordinate.empty() && !model_.coordinate(p.coordinate))
      throw OpenSimModelError(where + ".coordinate: the model has no coordinate '" + p.coordinate + "'");
    if (p.kind == OpenSimPathPointKind::Moving)
      for (const OpenSimFunction& f : p.moving_location)
        if (f.kind() == OpenSimFunction::Kind::Unsupported)
          throw OpenSimModelError(where + ": location function '" + f.typeName() + "' is not evaluated by flatsos");
  }
  for (const OpenSimPathWrap& w : path_.wraps) {
    WrapInfo info;
    for (std::size_t i = 0; i < paths.wrap_objects.size(); ++i)
      if (paths.wrap_objects[i].name == w.wrap_object) info.object = &paths.wrap_objects[i], info.object_index = static_cast<int>(i);
    const std::string where = muscle + ": PathWrap '" + w.name + "'";
    if (!info.object) throw OpenSimModelError(where + ".wrap_object: no wrap object '" + w.wrap_object + "'");
    const OpenSimWrapSurface s = info.object->surface;
    if (s != OpenSimWrapSurface::Cylinder && s != OpenSimWrapSurface::Sphere && s != OpenSimWrapSurface::Ellipsoid)
      throw OpenSimModelError(where + ": " + info.object->type + " '" + info.object->name +
                              "' is not evaluated by flatsos (WrapCylinder, WrapSphere and WrapEllipsoid are)");
    info.body = body_index(info.object->body, where + ": " + info.object->type + " '" + info.object->name + "'");
    wraps_.push_back(info);
  }
}

std::vector<std::string> GeometryPathEvaluator::coordinates() const {
  std::vector<std::string> used;
  for (const auto& chain : chains_)
    for (const OpenSimJoint* joint : chain) used.insert(used.end(), joint->coordinates.begin(), joint->coordinates.end());
  for (const OpenSimPathPoint& p : path_.points)
    if (p.kind != OpenSimPathPointKind::Fixed && !p.coordinate.empty()) used.push_back(p.coordinate);
  for (const OpenSimCoupler& c : model_.couplers)
    if (std::find(used.begin(), used.end(), c.dependent) != used.end()) used.push_back(c.independent);
  std::vector<std::string> out;
  for (const OpenSimCoordinate& c : model_.coordinates)
    if (std::find(used.begin(), used.end(), c.name) != used.end()) out.push_back(c.name);
  return out;
}

Eigen::Vector3d GeometryPathEvaluator::point_location(int i, const OpenSimCoordinateValues& q, Eigen::Vector3d* rate) const {
  const OpenSimPathPoint& p = path_.points[i];
  if (p.kind != OpenSimPathPointKind::Moving) return p.frame_in_body * p.location_m;
  // OpenSim clamps the coordinate to its range for the place, not for the rate.
  double x = 0.0, unclamped = 0.0;
  if (!p.coordinate.empty()) {
    const auto& range = model_.coordinate(p.coordinate)->range;
    unclamped = value_of(q, p.coordinate);
    x = std::clamp(unclamped, range[0], range[1]);
  }
  Eigen::Vector3d location, local_rate = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) {
    location[k] = p.moving_location[k].value(x);
    if (!p.coordinate.empty()) local_rate[k] = p.moving_location[k].derivative(unclamped);
  }
  if (rate) *rate = p.frame_in_body.linear() * local_rate;
  return p.frame_in_body * location;
}

bool GeometryPathEvaluator::add_active_points(const OpenSimCoordinateValues& q, Workspace& w) const {
  for (std::size_t i = 0; i < path_.points.size(); ++i) {
    const OpenSimPathPoint& p = path_.points[i];
    if (p.kind == OpenSimPathPointKind::Conditional) {
      if (p.coordinate.empty()) continue;
      const double v = value_of(q, p.coordinate);
      if (!(v >= p.active_range[0] - 1e-5 && v <= p.active_range[1] + 1e-5)) continue;
    }
    Node node;
    node.body = point_body_[i];
    node.point = static_cast<int>(i);
    node.local = point_location(static_cast<int>(i), q, &node.moving_rate_local);
    node.ground = w.poses[node.body] * node.local;
    w.path.push_back(node);
  }
  return w.path.size() >= 2;
}

void GeometryPathEvaluator::body_poses(const OpenSimCoordinateValues& q, std::vector<Eigen::Isometry3d>& poses) const {
  poses.resize(bodies_.size());
  for (std::size_t b = 0; b < bodies_.size(); ++b)
    poses[b] = bodies_[b] == "ground" ? Eigen::Isometry3d::Identity() : opensim_body_in_ground(model_, bodies_[b], q);
}

void GeometryPathEvaluator::compute(const OpenSimCoordinateValues& q, Workspace& w, bool surfaces) const {
  body_poses(q, w.poses);
  w.path.clear();
  w.surfaces.resize(wraps_.size());
  w.seen.resize(wraps_.size());
  w.seen_set.assign(wraps_.size(), {false, false});
  if (add_active_points(q, w)) apply_wraps(w, surfaces);
  w.length = w.path_length();
}

void GeometryPathEvaluator::apply_wraps(Workspace& w, bool surfaces) const {
  const int count = static_cast<int>(wraps_.size());
  if (count < 1) return;
  w.order.resize(count);
  w.results.assign(count, WrapAction::NoWrap);
  for (int i = 0; i < count; ++i) w.order[i] = i;
  const int passes = count < 2 ? 1 : 8;
  auto remove_wrap = [&w](int k) {
    w.path.erase(std::remove_if(w.path.begin(), w.path.end(), [k](const Node& n) { return n.wrap == k; }), w.path.end());
  };
  double last_length = std::numeric_limits<double>::infinity();
  for (int pass = 0; pass < passes; ++pass) {
    for (int i = 0; i < count; ++i) {
      w.results[i] = WrapAction::NoWrap;
      remove_wrap(w.order[i]);
      if (!wraps_[w.order[i]].object->active) continue;
      if (!apply_one_wrap(w.order[i], w, surfaces, w.results[i])) return;  // OpenSim abandons all wraps
    }
    const double length = w.path_length();
    if (std::abs(length - last_length) < 0.0005) break;
    last_length = length;
    if (pass == 0 && count > 1 && w.results[0] == WrapAction::NoWrap && w.results[1] == WrapAction::InsideRadius) {
      w.order[0] = 1;
      w.order[1] = 0;
      remove_wrap(0);
    }
  }
}

// One PathWrap against the current path; false when its range holds no active point.
bool GeometryPathEvaluator::apply_one_wrap(int k, Workspace& w, bool surfaces, WrapAction& last_result) const {
  const OpenSimPathWrap& wrap = path_.wraps[k];
  const WrapInfo& info = wraps_[k];
  const int point_count = static_cast<int>(path_.points.size());
  const int first = wrap.range[0] < 1 ? 0 : wrap.range[0] - 1;
  const int last = wrap.range[1] < 1 ? point_count - 1 : wrap.range[1] - 1;
  auto active = [&w](int point) {
    return std::any_of(w.path.begin(), w.path.end(), [point](const Node& n) { return n.point == point; });
  };
  int start_point = first, end_point = last;
  while (start_point <= last && !active(start_point)) ++start_point;
  if (start_point > last) return false;
  while (end_point >= first && !active(end_point)) --end_point;
  if (end_point < first) return false;
  int start = -1, end = -1;
  for (int j = 0; j < static_cast<int>(w.path.size()); ++j) {
    if (w.path[j].point == start_point) start = j;
    if (w.path[j].point == end_point) end = j;
  }
  if (start < 0 || end < 0) return false;

  const Eigen::Isometry3d ground_to_body = w.poses[info.body].inverse();
  const bool skip_tangent_adjustment = path_.wraps.size() == 1 && !opensim_2_wrapping_;
  std::vector<Eigen::Vector3d>* drawn = surfaces ? &w.scratch : nullptr;
  WrapLineResult best;
  int insert_at = -1;
  double least_change = std::numeric_limits<double>::infinity();
  for (int a = start; a < end; ++a) {
    const Node& p1 = w.path[a];
    const Node& p2 = w.path[a + 1];
    if (p1.object >= 0 && p1.object == p2.object) continue;
    const WrapLineResult r = wrap_segment(*info.object, ground_to_body * p1.ground, ground_to_body * p2.ground, wrap.method, skip_tangent_adjustment, drawn);
    last_result = r.action;
    if (r.action == WrapAction::MandatoryWrap) {
      best = r, insert_at = a + 1;
      if (surfaces) w.surfaces[k] = w.scratch;
      break;
    }
    if (r.action != WrapAction::Wrapped) continue;
    const Eigen::Vector3d r1 = w.poses[info.body] * r.r1, r2 = w.poses[info.body] * r.r2;
    const Eigen::Vector3d& g1 = w.ground_as_seen(p1);
    const Eigen::Vector3d& g2 = w.ground_as_seen(p2);
    const double change = (g1 - r1).norm() + r.surface_length_m + (g2 - r2).norm() - (g1 - g2).norm();
    if (change < least_change) {
      best = r, insert_at = a + 1, least_change = change;
      if (surfaces) w.surfaces[k] = w.scratch;
    }
  }
  if (insert_at < 0) return true;
  Node r1, r2;
  r1.body = r2.body = info.body;
  r1.wrap = r2.wrap = k;
  r1.object = r2.object = info.object_index;
  r1.local = best.r1, r2.local = best.r2;
  r1.ground = w.poses[info.body] * best.r1, r2.ground = w.poses[info.body] * best.r2;
  r2.second = true;
  r2.surface_length = best.surface_length_m;
  w.path.insert(w.path.begin() + insert_at, {r1, r2});
  return true;
}

double GeometryPathEvaluator::length(const OpenSimCoordinateValues& q) const {
  Workspace& w = thread_workspace<Workspace>();
  compute(q, w, false);
  return w.length;
}

PathEvaluation GeometryPathEvaluator::evaluate(const OpenSimCoordinateValues& q, bool surfaces) const {
  Workspace& w = thread_workspace<Workspace>();
  compute(q, w, surfaces);
  PathEvaluation out;
  out.length_m = w.length;
  for (const Node& n : w.path) {
    EvaluatedPathPoint p;
    p.ground_m = n.ground;
    p.body = bodies_[n.body];
    p.path_point = n.point;
    p.path_wrap = n.wrap;
    p.leaves_surface = n.second;
    p.surface_length_m = n.surface_length;
    if (surfaces && n.second)
      for (const Eigen::Vector3d& s : w.surfaces[n.wrap]) p.surface_ground_m.push_back(w.poses[n.body] * s);
    out.points.push_back(std::move(p));
  }
  return out;
}

}  // namespace flatsos::plugin
