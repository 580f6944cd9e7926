// Reads OpenSim's GeometryPaths and wrap objects out of an .osim document: OpenSim 4 (sockets:
// socket_parent_frame, socket_coordinate, socket_x_coordinate) and OpenSim 3 (<body>,
// <coordinate>, <x_coordinate>) spellings. Defaults are OpenSim's own where a property is left
// out (a cylinder of radius 1 and length 1, a sphere of radius 0.05, ...).

#include <set>

#include "../io/opensim_text.hpp"
#include "flatsos/plugin/paths/geometry_path.hpp"
#include "osim_frames.hpp"

namespace flatsos::plugin {

namespace {

using osim_xml::Element;
using osim_xml::FramePose;
using osim_xml::FrameTable;
using osim_xml::Reader;

// The coordinate a socket or an OpenSim 3 name refers to, or "".
std::string coordinate_name(const Reader& r, Element& e, const char* socket, const char* old_tag) {
  const std::string value = e.hasElement(socket) ? r.text(e, socket) : r.text(e, old_tag);
  return opensim_text::last_component(value);
}

WrapQuadrant read_quadrant(const Reader& r, Element& e, const std::string& where) {
  const std::string q = r.text(e, "quadrant");
  if (q.empty() || q == "Unassigned" || q == "all" || q == "All" || q == "ALL") return {};
  for (int axis = 0; axis < 3; ++axis) {
    const std::string lower(1, static_cast<char>('x' + axis)), upper(1, static_cast<char>('X' + axis));
    if (q == lower || q == upper || q == "+" + lower || q == "+" + upper) return {axis, 1};
    if (q == "-" + lower || q == "-" + upper) return {axis, -1};
  }
  r.fail(where + ".quadrant", "'" + q + "' is not one of x, +x, -x, y, +y, -y, z, +z, -z (any case) or all");
}

OpenSimWrapObject read_wrap_object(const Reader& r, Element& e, const FramePose& frame) {
  OpenSimWrapObject w;
  w.type = e.getElementTag();
  w.name = e.getOptionalAttributeValue("name", "");
  const std::string where = w.type + " '" + w.name + "'";
  if (w.name.empty()) r.fail("WrapObjectSet of '" + frame.body + "'", "a " + w.type + " without a name");
  w.body = frame.body;
  w.active = r.bool_or(e, "active", where, true);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = r.vec3_or(e, "translation", where, Eigen::Vector3d::Zero());
  pose.linear() = osim_xml::body_fixed_xyz(r.vec3_or(e, "xyz_body_rotation", where, Eigen::Vector3d::Zero()));
  w.pose_in_body = frame.in_body * pose;
  w.quadrant = read_quadrant(r, e, where);
  if (w.type == "WrapCylinder") {
    w.surface = OpenSimWrapSurface::Cylinder;
    w.radius_m = r.number_or(e, "radius", where, 1.0);
    w.length_m = r.number_or(e, "length", where, 1.0);
    if (!(w.radius_m >= 0.0)) r.fail(where + ".radius", "must be >= 0");
    if (!(w.length_m >= 0.0)) r.fail(where + ".length", "must be >= 0");
  } else if (w.type == "WrapSphere") {
    w.surface = OpenSimWrapSurface::Sphere;
    w.radius_m = r.number_or(e, "radius", where, 0.05);
    if (!(w.radius_m >= 0.0)) r.fail(where + ".radius", "must be >= 0");
  } else if (w.type == "WrapEllipsoid") {
    w.surface = OpenSimWrapSurface::Ellipsoid;
    w.dimensions_m = r.vec3_or(e, "dimensions", where, Eigen::Vector3d::Constant(0.05));
    if (!(w.dimensions_m.minCoeff() > 0.0)) r.fail(where + ".dimensions", "every radius must be > 0");
  } else if (w.type == "WrapTorus") {
    w.surface = OpenSimWrapSurface::Torus;
    w.inner_radius_m = r.number_or(e, "inner_radius", where, 0.01);
    w.outer_radius_m = r.number_or(e, "outer_radius", where, 0.05);
    if (!(w.inner_radius_m > 0.0)) r.fail(where + ".inner_radius", "must be > 0");
    if (!(w.outer_radius_m > 0.0)) r.fail(where + ".outer_radius", "must be > 0");
  }
  return w;
}

std::vector<OpenSimWrapObject> read_wrap_objects(const Reader& r, const FrameTable& frames) {
  std::vector<OpenSimWrapObject> out;
  std::set<std::string> names;
  for (const auto& [frame, element] : frames.frameElements()) {
    Element holder = element;
    Element list = osim_xml::set_objects(holder, "WrapObjectSet");
    if (!list.isValid()) continue;
    for (auto it = list.element_begin(); it != list.element_end(); ++it) {
      Element e = *it;
      out.push_back(read_wrap_object(r, e, frame));
      if (!names.insert(out.back().name).second) r.fail(out.back().type + " '" + out.back().name + "'", "a second wrap object of this name");
    }
  }
  return out;
}

void read_moving_point(const Reader& r, Element& e, const std::string& where, OpenSimPathPoint& p) {
  p.kind = OpenSimPathPointKind::Moving;
  const char* axes[3] = {"x", "y", "z"};
  std::string coordinates[3];
  for (int k = 0; k < 3; ++k) {
    const std::string location = std::string(axes[k]) + "_location";
    coordinates[k] = coordinate_name(r, e, ("socket_" + std::string(axes[k]) + "_coordinate").c_str(),
                                     (std::string(axes[k]) + "_coordinate").c_str());
    p.moving_location[k] = OpenSimFunction::constant(0.0);
    if (Element holder = e.getOptionalElement(location); holder.isValid())
      p.moving_location[k] = r.function(holder, where + "." + location, OpenSimFunction::constant(0.0));
  }
  if (coordinates[0] != coordinates[1] || coordinates[0] != coordinates[2])
    r.fail(where, "x, y and z must follow the same coordinate (OpenSim requires it), got '" + coordinates[0] + "', '" +
                      coordinates[1] + "', '" + coordinates[2] + "'");
  p.coordinate = coordinates[0];
}

OpenSimPathPoint read_point(const Reader& r, Element& e, const FrameTable& frames, const std::string& where_path) {
  OpenSimPathPoint p;
  p.name = e.getOptionalAttributeValue("name", "");
  const std::string type = e.getElementTag();
  const std::string where = where_path + ": " + type + " '" + p.name + "'";
  std::string frame = r.text(e, "socket_parent_frame");
  if (frame.empty()) frame = r.text(e, "body");
  if (frame.empty()) r.fail(where, "missing <socket_parent_frame> (or OpenSim 3's <body>)");
  const FramePose pose = frames.resolve(frame, where + ".socket_parent_frame");
  p.body = pose.body;
  p.frame_in_body = pose.in_body;
  if (type == "PathPoint" || type == "ConditionalPathPoint") {
    p.location_m = r.vec3_or(e, "location", where, Eigen::Vector3d::Zero());
  } else if (type == "MovingPathPoint") {
    read_moving_point(r, e, where, p);
  } else {
    r.fail(where, "not a path point flatsos reads (PathPoint, ConditionalPathPoint, MovingPathPoint)");
  }
  if (type == "ConditionalPathPoint") {
    p.kind = OpenSimPathPointKind::Conditional;
    p.coordinate = coordinate_name(r, e, "socket_coordinate", "coordinate");
    if (e.hasElement("range")) {
      const std::vector<double> range = r.numbers(e, "range", where, 2);
      p.active_range = {range[0], range[1]};
    }
  }
  return p;
}

WrapMethod read_method(const Reader& r, Element& e, const std::string& where) {
  const std::string m = r.text(e, "method");
  if (m.empty() || m == "Unassigned" || m == "hybrid" || m == "Hybrid" || m == "HYBRID") return WrapMethod::Hybrid;
  if (m == "midpoint" || m == "Midpoint" || m == "MIDPOINT") return WrapMethod::Midpoint;
  if (m == "axial" || m == "Axial" || m == "AXIAL") return WrapMethod::Axial;
  r.fail(where + ".method", "'" + m + "' is not hybrid, midpoint or axial");
}

OpenSimPathWrap read_wrap(const Reader& r, Element& e, const std::vector<OpenSimWrapObject>& objects, std::size_t point_count,
                          const std::string& where_path) {
  OpenSimPathWrap w;
  w.name = e.getOptionalAttributeValue("name", "");
  const std::string where = where_path + ": PathWrap '" + w.name + "'";
  w.wrap_object = r.text(e, "wrap_object");
  bool known = false;
  for (const OpenSimWrapObject& o : objects) known = known || o.name == w.wrap_object;
  if (!known) r.fail(where + ".wrap_object", "no wrap object is named '" + w.wrap_object + "'");
  w.method = read_method(r, e, where);
  if (e.hasElement("range")) {
    const std::vector<double> range = r.numbers(e, "range", where, 2);
    for (int k = 0; k < 2; ++k) {
      if (range[k] != static_cast<double>(static_cast<int>(range[k])) || range[k] > static_cast<double>(point_count))
        r.fail(where + ".range", "must be whole numbers up to the path's " + std::to_string(point_count) + " points (or -1)");
      w.range[k] = static_cast<int>(range[k]);
    }
  }
  return w;
}

OpenSimGeometryPath read_path(const Reader& r, Element& path, const std::string& force, const FrameTable& frames,
                              const std::vector<OpenSimWrapObject>& objects) {
  OpenSimGeometryPath out;
  out.muscle = force;
  if (Element points = osim_xml::set_objects(path, "PathPointSet"); points.isValid())
    for (auto it = points.element_begin(); it != points.element_end(); ++it) {
      Element e = *it;
      out.points.push_back(read_point(r, e, frames, force));
    }
  if (Element wraps = osim_xml::set_objects(path, "PathWrapSet"); wraps.isValid())
    for (auto it = wraps.element_begin("PathWrap"); it != wraps.element_end(); ++it) {
      Element e = *it;
      out.wraps.push_back(read_wrap(r, e, objects, out.points.size(), force));
    }
  return out;
}

}  // namespace

const OpenSimGeometryPath* OpenSimGeometryPaths::path(const std::string& muscle) const {
  for (const OpenSimGeometryPath& p : paths)
    if (p.muscle == muscle) return &p;
  return nullptr;
}

const OpenSimWrapObject* OpenSimGeometryPaths::wrapObject(const std::string& name) const {
  for (const OpenSimWrapObject& w : wrap_objects)
    if (w.name == name) return &w;
  return nullptr;
}

OpenSimGeometryPaths parse_opensim_geometry_paths(const std::string& xml, const std::string& source) {
  const Reader r(source);
  SimTK::Xml::Document document;
  try {
    document.readFromString(xml);
  } catch (const std::exception& e) {
    r.fail("document", "not an XML document (" + std::string(e.what()) + ")");
  }
  Element root = document.getRootElement();
  Element model = root.getElementTag() == "Model" ? root : root.getOptionalElement("Model");
  if (!model.isValid()) r.fail("document", "no <Model> (not an OpenSim model file)");
  const FrameTable frames(r, model);
  OpenSimGeometryPaths out;
  out.wrap_objects = read_wrap_objects(r, frames);
  std::set<std::string> names;
  if (Element list = osim_xml::set_objects(model, "ForceSet"); list.isValid())
    for (auto it = list.element_begin(); it != list.element_end(); ++it) {
      Element force = *it;
      Element path = osim_xml::find_below(force, "GeometryPath");
      if (!path.isValid()) continue;
      const std::string name = force.getOptionalAttributeValue("name", "");
      if (!names.insert(name).second) r.fail(force.getElementTag() + " '" + name + "'", "a second force of this name");
      out.paths.push_back(read_path(r, path, name, frames, out.wrap_objects));
    }
  return out;
}

OpenSimGeometryPaths read_opensim_geometry_paths(const std::string& file) {
  const std::optional<std::string> text = opensim_text::file_text(file);
  if (!text) throw OpenSimFileError("'" + file + "': cannot open the OpenSim model file");
  return parse_opensim_geometry_paths(*text, file);
}

}  // namespace flatsos::plugin
