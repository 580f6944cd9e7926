#include "flatsos/plugin/io/opensim_model.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <SimTKcommon.h>

#include "opensim_text.hpp"

namespace flatsos::plugin {

namespace {

using opensim_text::last_component;
using opensim_text::words;

using Element = SimTK::Xml::Element;

// Names where a value came from in every error: "'file': Body 'femur_r'.mass".
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw OpenSimFileError("'" + source_ + "': " + where + ": " + what);
  }

  std::vector<double> numbers(const std::string& text, const std::string& where, std::size_t count = 0) const {
    std::vector<double> out;
    for (const std::string& w : words(text)) {
      const std::optional<double> value = opensim_text::finite_number(w);
      if (!value) fail(where, "'" + w + "' is not a finite number");
      out.push_back(*value);
    }
    if (count && out.size() != count)
      fail(where, "needs " + std::to_string(count) + " numbers, got " + std::to_string(out.size()));
    return out;
  }
  std::vector<double> numbers(Element& e, const char* tag, const std::string& where, std::size_t count) const {
    if (!e.hasElement(tag)) fail(where, std::string("missing <") + tag + ">");
    return numbers(e.getRequiredElementValue(tag), where + "." + tag, count);
  }
  double number(Element& e, const char* tag, const std::string& where) const { return numbers(e, tag, where, 1)[0]; }
  double optional_number(Element& e, const char* tag, const std::string& where, double fallback) const {
    return e.hasElement(tag) ? number(e, tag, where) : fallback;
  }
  Eigen::Vector3d vec3(Element& e, const char* tag, const std::string& where) const {
    const std::vector<double> v = numbers(e, tag, where, 3);
    return {v[0], v[1], v[2]};
  }

  OpenSimFunction function(Element& container, const std::string& where) const {
    for (auto it = container.element_begin(); it != container.element_end(); ++it) {
      Element f = *it;
      const std::string tag = f.getElementTag();
      const std::string at = where + "." + tag;
      if (tag == "Constant") return OpenSimFunction::constant(number(f, "value", at));
      if (tag == "LinearFunction") {
        const std::vector<double> c = numbers(f, "coefficients", at, 2);
        return OpenSimFunction::linear(c[0], c[1]);
      }
      if (tag == "PolynomialFunction") {
        const std::vector<double> c = numbers(f, "coefficients", at, 0);
        if (c.empty()) fail(at + ".coefficients", "no coefficients");
        return OpenSimFunction::polynomial(c);
      }
      if (tag == "SimmSpline") {
        try {
          return OpenSimFunction::simmSpline(numbers(f, "x", at, 0), numbers(f, "y", at, 0));
        } catch (const std::invalid_argument& e) {
          fail(at, e.what());
        }
      }
      if (tag == "MultiplierFunction") {
        if (!f.hasElement("function")) fail(at, "missing <function>");
        Element inner = f.getRequiredElement("function");
        return function(inner, at + ".function").scaled(optional_number(f, "scale", at, 1.0));
      }
      // Another function (it carries a name, as OpenSim writes functions) or a property.
      if (!f.getOptionalAttributeValue("name", "").empty()) return OpenSimFunction::unsupported(tag);
    }
    return OpenSimFunction::unsupported("(none)");
  }

 private:
  std::string source_;
};

// OpenSim's <orientation>: body-fixed X, then Y, then Z rotations.
Eigen::Matrix3d body_fixed_xyz(const Eigen::Vector3d& angles) {
  return (Eigen::AngleAxisd(angles[0], Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(angles[1], Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(angles[2], Eigen::Vector3d::UnitZ()))
      .toRotationMatrix();
}

OpenSimBody read_body(const Reader& r, Element& e) {
  OpenSimBody b;
  b.name = e.getOptionalAttributeValue("name", "");
  const std::string where = "Body '" + b.name + "'";
  if (b.name.empty()) r.fail("BodySet", "a Body without a name");
  b.mass_kg = r.number(e, "mass", where);
  if (!(b.mass_kg >= 0.0)) r.fail(where + ".mass", "must be >= 0");
  b.mass_center_m = r.vec3(e, "mass_center", where);
  const std::vector<double> I = r.numbers(e, "inertia", where, 6);  // xx yy zz xy xz yz
  b.inertia_kg_m2 << I[0], I[3], I[4], I[3], I[1], I[5], I[4], I[5], I[2];
  return b;
}

struct FrameRecord {
  std::string body;
  Eigen::Isometry3d offset = Eigen::Isometry3d::Identity();
};
using FrameRecords = std::vector<std::pair<std::string, FrameRecord>>;

// A joint's socket: one of its own PhysicalOffsetFrames (by name or "<joint>/<frame>"), or a body.
FrameRecord resolve_frame(const Reader& r, const std::string& socket, const FrameRecords& frames, const std::set<std::string>& bodies,
                          const std::string& where) {
  const std::string name = last_component(socket);
  for (const auto& [frame_name, record] : frames)
    if (frame_name == name) return record;
  if (name == "ground" || bodies.count(name)) return FrameRecord{name, Eigen::Isometry3d::Identity()};
  r.fail(where, "frame '" + socket + "' is neither one of the joint's frames nor a body");
}

// The joint's own PhysicalOffsetFrames, each on a body.
FrameRecords read_offset_frames(const Reader& r, Element& e, const std::set<std::string>& bodies, const std::string& where) {
  FrameRecords frames;
  if (!e.hasElement("frames")) return frames;
  Element list = e.getRequiredElement("frames");
  for (auto it = list.element_begin("PhysicalOffsetFrame"); it != list.element_end(); ++it) {
    Element f = *it;
    const std::string frame_name = f.getOptionalAttributeValue("name", "");
    const std::string at = where + ".frames." + frame_name;
    if (!f.hasElement("socket_parent")) r.fail(at, "missing <socket_parent>");
    const std::string parent = last_component(f.getRequiredElementValue("socket_parent"));
    if (parent != "ground" && !bodies.count(parent))
      r.fail(at + ".socket_parent", "'" + parent + "' is not a body (offsets of offsets are not read)");
    FrameRecord record{parent, Eigen::Isometry3d::Identity()};
    record.offset.translation() = r.vec3(f, "translation", at);
    record.offset.linear() = body_fixed_xyz(r.vec3(f, "orientation", at));
    frames.emplace_back(frame_name, record);
  }
  return frames;
}

// The joint's parent and child bodies with the offsets of its frames on them.
void read_sockets(const Reader& r, Element& e, const std::set<std::string>& bodies, const std::string& where, OpenSimJoint& j) {
  const FrameRecords frames = read_offset_frames(r, e, bodies, where);
  for (const char* socket : {"socket_parent_frame", "socket_child_frame"})
    if (!e.hasElement(socket)) r.fail(where, std::string("missing <") + socket + ">");
  const FrameRecord parent = resolve_frame(r, e.getRequiredElementValue("socket_parent_frame"), frames, bodies, where + ".socket_parent_frame");
  const FrameRecord child = resolve_frame(r, e.getRequiredElementValue("socket_child_frame"), frames, bodies, where + ".socket_child_frame");
  j.parent_body = parent.body;
  j.parent_offset = parent.offset;
  j.child_body = child.body;
  j.child_offset = child.offset;
  if (j.child_body == "ground") r.fail(where + ".socket_child_frame", "ground cannot be a joint's child");
}

// The joint's coordinates, appended to the model's and named in the joint.
void read_coordinates(const Reader& r, Element& e, const std::string& where, OpenSimJoint& j, std::vector<OpenSimCoordinate>& coordinates) {
  if (!e.hasElement("coordinates")) return;
  Element list = e.getRequiredElement("coordinates");
  for (auto it = list.element_begin("Coordinate"); it != list.element_end(); ++it) {
    Element c = *it;
    OpenSimCoordinate coordinate;
    coordinate.name = c.getOptionalAttributeValue("name", "");
    coordinate.joint = j.name;
    const std::string at = where + ".Coordinate '" + coordinate.name + "'";
    if (coordinate.name.empty()) r.fail(where, "a Coordinate without a name");
    coordinate.default_value = r.optional_number(c, "default_value", at, 0.0);
    if (c.hasElement("range")) {
      const std::vector<double> range = r.numbers(c, "range", at, 2);
      if (!(range[0] <= range[1])) r.fail(at + ".range", "lower end above upper end");
      coordinate.range = {range[0], range[1]};
    } else {
      coordinate.range = {-SimTK::Infinity, SimTK::Infinity};
    }
    coordinate.locked = c.getOptionalElementValueAs<bool>("locked", false);
    coordinates.push_back(coordinate);
    j.coordinates.push_back(coordinate.name);
  }
}

// A PinJoint's or SliderJoint's one axis: about z or along x, turned by its one coordinate.
void add_pin_or_slider_axis(const Reader& r, const std::string& where, OpenSimJoint& j) {
  if (j.coordinates.size() != 1) r.fail(where, "needs exactly one coordinate");
  OpenSimTransformAxis axis;
  axis.name = j.type == "PinJoint" ? "rotation" : "translation";
  axis.rotation = j.type == "PinJoint";
  axis.axis = j.type == "PinJoint" ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
  axis.coordinates = j.coordinates;
  axis.function = OpenSimFunction::identity();
  j.axes.push_back(axis);
}

// A CustomJoint's SpatialTransform: its TransformAxes, rotations first.
void read_spatial_transform(const Reader& r, Element& e, const std::string& where, OpenSimJoint& j) {
  if (!e.hasElement("SpatialTransform")) r.fail(where, "missing <SpatialTransform>");
  Element transform = e.getRequiredElement("SpatialTransform");
  for (auto it = transform.element_begin("TransformAxis"); it != transform.element_end(); ++it) {
    Element a = *it;
    OpenSimTransformAxis axis;
    axis.name = a.getOptionalAttributeValue("name", "");
    const std::string at = where + ".SpatialTransform." + axis.name;
    axis.rotation = axis.name.rfind("rotation", 0) == 0;
    if (!axis.rotation && axis.name.rfind("translation", 0) != 0)
      r.fail(at, "a TransformAxis must be named rotation1..3 or translation1..3");
    axis.axis = r.vec3(a, "axis", at);
    if (!(axis.axis.norm() > 0.0)) r.fail(at + ".axis", "has length 0");
    axis.axis.normalize();
    axis.coordinates = words(a.getOptionalElementValue("coordinates", ""));
    for (const std::string& c : axis.coordinates)
      if (std::find(j.coordinates.begin(), j.coordinates.end(), c) == j.coordinates.end())
        r.fail(at + ".coordinates", "'" + c + "' is not one of the joint's coordinates");
    axis.function = r.function(a, at);
    if (axis.function.typeName() == "(none)")
      axis.function = axis.coordinates.size() == 1 ? OpenSimFunction::identity() : OpenSimFunction::constant(0.0);
    j.axes.push_back(axis);
  }
  std::stable_partition(j.axes.begin(), j.axes.end(), [](const OpenSimTransformAxis& a) { return a.rotation; });
}

OpenSimJoint read_joint(const Reader& r, Element& e, const std::set<std::string>& bodies, std::vector<OpenSimCoordinate>& coordinates) {
  OpenSimJoint j;
  j.type = e.getElementTag();
  j.name = e.getOptionalAttributeValue("name", "");
  const std::string where = j.type + " '" + j.name + "'";
  if (j.name.empty()) r.fail("JointSet", "a " + j.type + " without a name");
  read_sockets(r, e, bodies, where, j);
  const std::size_t first_coordinate = coordinates.size();
  read_coordinates(r, e, where, j, coordinates);
  if (j.type == "PinJoint" || j.type == "SliderJoint") add_pin_or_slider_axis(r, where, j);
  else if (j.type == "CustomJoint") read_spatial_transform(r, e, where, j);
  // A coordinate is a translation when only translation axes use it.
  for (std::size_t k = first_coordinate; k < coordinates.size(); ++k) {
    bool rotates = false, translates = false;
    for (const auto& a : j.axes)
      if (std::find(a.coordinates.begin(), a.coordinates.end(), coordinates[k].name) != a.coordinates.end())
        (a.rotation ? rotates : translates) = true;
    coordinates[k].rotational = rotates || !translates;
  }
  return j;
}

void read_muscle_path_bodies(Element& e, std::vector<std::string>& bodies) {
  for (auto it = e.element_begin(); it != e.element_end(); ++it) {
    Element child = *it;
    if (child.getElementTag() == "socket_parent_frame") {
      const std::string body = last_component(child.getValue());
      if (std::find(bodies.begin(), bodies.end(), body) == bodies.end()) bodies.push_back(body);
    } else {
      read_muscle_path_bodies(child, bodies);
    }
  }
}

// The first element of this tag anywhere below e (depth first), or an invalid element.
Element find_below(Element& e, const std::string& tag) {
  for (auto it = e.element_begin(); it != e.element_end(); ++it) {
    Element child = *it;
    if (child.getElementTag() == tag) return child;
    Element found = find_below(child, tag);
    if (found.isValid()) return found;
  }
  return Element();
}

// The numbers (booleans as 1 and 0) that e's children without children of their own hold,
// keyed prefix + tag. An empty element (an optional property left unset) holds none.
void read_direct_properties(Element& e, const std::string& prefix, std::map<std::string, double>& properties) {
  for (auto it = e.element_begin(); it != e.element_end(); ++it) {
    Element child = *it;
    if (child.element_begin() != child.element_end()) continue;
    const std::vector<std::string> value = words(child.getValue());
    if (value.size() != 1) continue;
    const std::optional<double> number = value[0] == "true" ? 1.0 : value[0] == "false" ? 0.0 : opensim_text::finite_number(value[0]);
    if (number) properties[prefix + child.getElementTag()] = *number;
  }
}

OpenSimMuscle read_muscle(const Reader& r, Element& e) {
  OpenSimMuscle m;
  m.type = e.getElementTag();
  m.name = e.getOptionalAttributeValue("name", "");
  const std::string where = m.type + " '" + m.name + "'";
  m.max_isometric_force_N = r.number(e, "max_isometric_force", where);
  m.optimal_fiber_length_m = r.number(e, "optimal_fiber_length", where);
  m.tendon_slack_length_m = r.number(e, "tendon_slack_length", where);
  m.pennation_angle_at_optimal_rad = r.optional_number(e, "pennation_angle_at_optimal", where, 0.0);
  m.max_contraction_velocity_in_optimal_lengths_per_s =
      r.optional_number(e, "max_contraction_velocity", where, m.max_contraction_velocity_in_optimal_lengths_per_s);
  m.activation_time_constant_s = r.optional_number(e, "activation_time_constant", where, m.activation_time_constant_s);
  m.deactivation_time_constant_s = r.optional_number(e, "deactivation_time_constant", where, m.deactivation_time_constant_s);
  m.minimum_activation = r.optional_number(e, "minimum_activation", where, m.minimum_activation);
  for (const auto& [curve, value] : {std::pair<const char*, double*>{"TendonForceLengthCurve", &m.tendon_strain_at_one_norm_force},
                                     std::pair<const char*, double*>{"FiberForceLengthCurve", &m.passive_fiber_strain_at_one_norm_force}}) {
    Element c = find_below(e, curve);
    if (c.isValid()) *value = r.optional_number(c, "strain_at_one_norm_force", where + "." + curve, *value);
  }
  // Every number the muscle states directly (its model's own properties: Af, fiber_damping, ...),
  // and those of its curves (<ActiveForceLengthCurve>...) under "<curve>/<property>".
  read_direct_properties(e, "", m.properties);
  for (auto it = e.element_begin(); it != e.element_end(); ++it) {
    Element child = *it;
    const std::string tag = child.getElementTag();
    if (tag.size() > 5 && tag.compare(tag.size() - 5, 5, "Curve") == 0) read_direct_properties(child, tag + "/", m.properties);
  }
  Element path = find_below(e, "GeometryPath");
  if (path.isValid()) read_muscle_path_bodies(path, m.path_bodies);
  return m;
}

Element set_objects(Element& model, const char* set) {
  Element s = model.getOptionalElement(set);
  return s.isValid() ? s.getOptionalElement("objects") : Element();
}

}  // namespace

namespace {
// The first item whose `field` equals `value`, or nullptr.
template <class T>
const T* find_by(const std::vector<T>& items, std::string T::*field, const std::string& value) {
  for (const T& item : items)
    if (item.*field == value) return &item;
  return nullptr;
}
}  // namespace

const OpenSimBody* OpenSimModel::body(const std::string& n) const { return find_by(bodies, &OpenSimBody::name, n); }
const OpenSimJoint* OpenSimModel::joint(const std::string& n) const { return find_by(joints, &OpenSimJoint::name, n); }
const OpenSimJoint* OpenSimModel::jointOfChild(const std::string& b) const {
  return find_by(joints, &OpenSimJoint::child_body, b);
}
const OpenSimCoordinate* OpenSimModel::coordinate(const std::string& n) const {
  return find_by(coordinates, &OpenSimCoordinate::name, n);
}
const OpenSimMuscle* OpenSimModel::muscle(const std::string& n) const { return find_by(muscles, &OpenSimMuscle::name, n); }
const OpenSimCoupler* OpenSimModel::couplerOf(const std::string& dependent) const {
  return find_by(couplers, &OpenSimCoupler::dependent, dependent);
}

OpenSimModel parse_opensim_model(const std::string& xml, const std::string& source) {
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

  OpenSimModel out;
  out.name = model.getOptionalAttributeValue("name", "");
  if (model.hasElement("gravity")) out.gravity_m_per_s2 = r.vec3(model, "gravity", "Model");
  out.credits = model.getOptionalElementValue("credits", "");
  out.publications = model.getOptionalElementValue("publications", "");

  std::set<std::string> body_names;
  if (Element list = set_objects(model, "BodySet"); list.isValid())
    for (auto it = list.element_begin("Body"); it != list.element_end(); ++it) {
      out.bodies.push_back(read_body(r, *it));
      if (out.bodies.back().name == "ground" || !body_names.insert(out.bodies.back().name).second)
        r.fail("Body '" + out.bodies.back().name + "'", "given twice (or named ground)");
    }
  if (out.bodies.empty()) r.fail("BodySet", "no Body");

  if (Element list = set_objects(model, "JointSet"); list.isValid())
    for (auto it = list.element_begin(); it != list.element_end(); ++it) out.joints.push_back(read_joint(r, *it, body_names, out.coordinates));
  std::set<std::string> names;
  for (const auto& c : out.coordinates)
    if (!names.insert(c.name).second) r.fail("Coordinate '" + c.name + "'", "given twice");
  names.clear();
  for (const auto& j : out.joints)
    if (!names.insert(j.child_body).second) r.fail(j.type + " '" + j.name + "'", "body '" + j.child_body + "' is the child of two joints");

  if (Element list = set_objects(model, "ConstraintSet"); list.isValid())
    for (auto it = list.element_begin("CoordinateCouplerConstraint"); it != list.element_end(); ++it) {
      Element c = *it;
      OpenSimCoupler coupler;
      coupler.name = c.getOptionalAttributeValue("name", "");
      const std::string where = "CoordinateCouplerConstraint '" + coupler.name + "'";
      if (!c.getOptionalElementValueAs<bool>("isEnforced", true)) continue;
      const std::vector<std::string> independent = words(c.getOptionalElementValue("independent_coordinate_names", ""));
      if (independent.size() != 1) r.fail(where, "needs exactly one independent coordinate (multi-coordinate couplers are not read)");
      coupler.independent = independent[0];
      coupler.dependent = c.getOptionalElementValue("dependent_coordinate_name", "");
      if (!c.hasElement("coupled_coordinates_function")) r.fail(where, "missing <coupled_coordinates_function>");
      Element f = c.getRequiredElement("coupled_coordinates_function");
      coupler.function = r.function(f, where + ".coupled_coordinates_function");
      coupler.scale = r.optional_number(c, "scale_factor", where, 1.0);
      for (const std::string* name : {&coupler.independent, &coupler.dependent})
        if (!out.coordinate(*name)) r.fail(where, "unknown coordinate '" + *name + "'");
      out.couplers.push_back(coupler);
    }

  if (Element list = set_objects(model, "ForceSet"); list.isValid())
    for (auto it = list.element_begin(); it != list.element_end(); ++it) {
      Element f = *it;
      if (!f.hasElement("max_isometric_force") || !f.hasElement("optimal_fiber_length") || !f.hasElement("tendon_slack_length"))
        continue;  // not a Hill muscle (a CoordinateActuator, a spring, ...)
      out.muscles.push_back(read_muscle(r, f));
      if (!names.insert("muscle:" + out.muscles.back().name).second)
        r.fail(out.muscles.back().type + " '" + out.muscles.back().name + "'", "given twice");
    }
  return out;
}

OpenSimModel read_opensim_model(const std::string& file) {
  const std::optional<std::string> text = opensim_text::file_text(file);
  if (!text) throw OpenSimFileError("'" + file + "': cannot open the OpenSim model file");
  return parse_opensim_model(*text, file);
}

}  // namespace flatsos::plugin
