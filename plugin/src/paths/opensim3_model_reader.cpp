// OpenSim 3 model files (joints nested in bodies) into OpenSimModel: see opensim3_model.hpp.
// The conversion is OpenSim 4's own (Joint::updateFromXMLNode for version < 30500): the parent
// offset frame from location_in_parent / orientation_in_parent, the child offset frame from
// location / orientation, both body-fixed XYZ.

#include <algorithm>
#include <set>

#include "../io/opensim_text.hpp"
#include "flatsos/plugin/paths/opensim3_model.hpp"
#include "osim_xml.hpp"

namespace flatsos::plugin {

namespace {

using osim_xml::Element;
using osim_xml::Reader;

Eigen::Isometry3d offset(const Reader& r, Element& joint, const char* location, const char* orientation, const std::string& where) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = r.vec3_or(joint, location, where, Eigen::Vector3d::Zero());
  X.linear() = osim_xml::body_fixed_xyz(r.vec3_or(joint, orientation, where, Eigen::Vector3d::Zero()));
  return X;
}

void read_coordinates(const Reader& r, Element& joint, const std::string& where, OpenSimJoint& j, OpenSimModel& model) {
  Element list = osim_xml::set_objects(joint, "CoordinateSet");
  if (!list.isValid()) return;
  for (auto it = list.element_begin("Coordinate"); it != list.element_end(); ++it) {
    Element c = *it;
    OpenSimCoordinate coordinate;
    coordinate.name = c.getOptionalAttributeValue("name", "");
    coordinate.joint = j.name;
    const std::string at = where + ".Coordinate '" + coordinate.name + "'";
    if (coordinate.name.empty()) r.fail(where, "a Coordinate without a name");
    coordinate.default_value = r.number_or(c, "default_value", at, 0.0);
    coordinate.range = {-SimTK::Infinity, SimTK::Infinity};
    if (c.hasElement("range")) {
      const std::vector<double> range = r.numbers(c, "range", at, 2);
      coordinate.range = {range[0], range[1]};
    }
    coordinate.locked = r.bool_or(c, "locked", at, false);
    const std::string motion = r.text(c, "motion_type");
    coordinate.rotational = motion != "translational";
    if (model.coordinate(coordinate.name)) r.fail(at, "given twice");
    model.coordinates.push_back(coordinate);
    j.coordinates.push_back(coordinate.name);
  }
}

void read_axes(const Reader& r, Element& joint, const std::string& where, OpenSimJoint& j) {
  if (j.type == "PinJoint" || j.type == "SliderJoint") {
    if (j.coordinates.size() != 1) r.fail(where, "needs exactly one coordinate");
    OpenSimTransformAxis axis;
    axis.name = j.type == "PinJoint" ? "rotation" : "translation";
    axis.rotation = j.type == "PinJoint";
    axis.axis = axis.rotation ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
    axis.coordinates = j.coordinates;
    axis.function = OpenSimFunction::identity();
    j.axes.push_back(axis);
    return;
  }
  if (j.type != "CustomJoint" || !joint.hasElement("SpatialTransform")) return;
  Element transform = joint.getRequiredElement("SpatialTransform");
  for (auto it = transform.element_begin("TransformAxis"); it != transform.element_end(); ++it) {
    Element a = *it;
    OpenSimTransformAxis axis;
    axis.name = a.getOptionalAttributeValue("name", "");
    const std::string at = where + ".SpatialTransform." + axis.name;
    axis.rotation = axis.name.rfind("rotation", 0) == 0;
    axis.axis = r.vec3_or(a, "axis", at, Eigen::Vector3d::Zero());
    if (!(axis.axis.norm() > 0.0)) r.fail(at + ".axis", "has length 0");
    axis.axis.normalize();
    axis.coordinates = opensim_text::words(r.text(a, "coordinates"));
    const OpenSimFunction none = OpenSimFunction::unsupported("(none)");
    axis.function = r.function(a, at, none);
    if (axis.function.typeName() == "(none)")
      axis.function = axis.coordinates.size() == 1 ? OpenSimFunction::identity() : OpenSimFunction::constant(0.0);
    j.axes.push_back(axis);
  }
  std::stable_partition(j.axes.begin(), j.axes.end(), [](const OpenSimTransformAxis& a) { return a.rotation; });
}

void read_joint(const Reader& r, Element& body, const std::string& body_name, OpenSimModel& model) {
  Element holder = body.getOptionalElement("Joint");
  if (!holder.isValid()) return;
  auto it = holder.element_begin();
  if (it == holder.element_end()) return;  // ground's empty <Joint>
  Element joint = *it;
  OpenSimJoint j;
  j.type = joint.getElementTag();
  j.name = joint.getOptionalAttributeValue("name", "");
  const std::string where = j.type + " '" + j.name + "'";
  j.parent_body = r.text(joint, "parent_body");
  if (j.parent_body.empty()) r.fail(where, "missing <parent_body>");
  if (r.bool_or(joint, "reverse", where, false)) r.fail(where + ".reverse", "reversed joints are not read");
  j.child_body = body_name;
  j.parent_offset = offset(r, joint, "location_in_parent", "orientation_in_parent", where);
  j.child_offset = offset(r, joint, "location", "orientation", where);
  read_coordinates(r, joint, where, j, model);
  read_axes(r, joint, where, j);
  model.joints.push_back(j);
}

OpenSimBody read_body(const Reader& r, Element& e, const std::string& name) {
  OpenSimBody b;
  b.name = name;
  const std::string where = "Body '" + name + "'";
  b.mass_kg = r.number_or(e, "mass", where, 0.0);
  b.mass_center_m = r.vec3_or(e, "mass_center", where, Eigen::Vector3d::Zero());
  const char* tags[6] = {"inertia_xx", "inertia_yy", "inertia_zz", "inertia_xy", "inertia_xz", "inertia_yz"};
  double I[6];
  for (int k = 0; k < 6; ++k) I[k] = r.number_or(e, tags[k], where, 0.0);
  b.inertia_kg_m2 << I[0], I[3], I[4], I[3], I[1], I[5], I[4], I[5], I[2];
  return b;
}

void read_couplers(const Reader& r, Element& model_element, OpenSimModel& model) {
  Element list = osim_xml::set_objects(model_element, "ConstraintSet");
  if (!list.isValid()) return;
  for (auto it = list.element_begin("CoordinateCouplerConstraint"); it != list.element_end(); ++it) {
    Element c = *it;
    OpenSimCoupler coupler;
    coupler.name = c.getOptionalAttributeValue("name", "");
    const std::string where = "CoordinateCouplerConstraint '" + coupler.name + "'";
    if (r.bool_or(c, "isDisabled", where, false)) continue;
    const std::vector<std::string> independent = opensim_text::words(r.text(c, "independent_coordinate_names"));
    if (independent.size() != 1) r.fail(where, "needs exactly one independent coordinate");
    coupler.independent = independent[0];
    coupler.dependent = r.text(c, "dependent_coordinate_name");
    if (!c.hasElement("coupled_coordinates_function")) r.fail(where, "missing <coupled_coordinates_function>");
    Element f = c.getRequiredElement("coupled_coordinates_function");
    coupler.function = r.function(f, where + ".coupled_coordinates_function", OpenSimFunction::unsupported("(none)"));
    coupler.scale = r.number_or(c, "scale_factor", where, 1.0);
    for (const std::string* name : {&coupler.independent, &coupler.dependent})
      if (!model.coordinate(*name)) r.fail(where, "unknown coordinate '" + *name + "'");
    model.couplers.push_back(coupler);
  }
}

}  // namespace

OpenSimModel parse_opensim3_model(const std::string& xml, const std::string& source) {
  const Reader r(source);
  SimTK::Xml::Document document;
  try {
    document.readFromString(xml);
  } catch (const std::exception& e) {
    r.fail("document", "not an XML document (" + std::string(e.what()) + ")");
  }
  Element root = document.getRootElement();
  Element model_element = root.getElementTag() == "Model" ? root : root.getOptionalElement("Model");
  if (!model_element.isValid()) r.fail("document", "no <Model> (not an OpenSim model file)");
  OpenSimModel model;
  model.name = model_element.getOptionalAttributeValue("name", "");
  model.gravity_m_per_s2 = r.vec3_or(model_element, "gravity", "Model", model.gravity_m_per_s2);
  if (Element list = osim_xml::set_objects(model_element, "BodySet"); list.isValid())
    for (auto it = list.element_begin("Body"); it != list.element_end(); ++it) {
      Element body = *it;
      const std::string name = body.getOptionalAttributeValue("name", "");
      if (name.empty()) r.fail("BodySet", "a Body without a name");
      if (name != "ground") model.bodies.push_back(read_body(r, body, name));
      read_joint(r, body, name, model);
    }
  read_couplers(r, model_element, model);
  return model;
}

OpenSimModel read_opensim3_model(const std::string& file) {
  const std::optional<std::string> text = opensim_text::file_text(file);
  if (!text) throw OpenSimFileError("'" + file + "': cannot open the OpenSim model file");
  return parse_opensim3_model(*text, file);
}

}  // namespace flatsos::plugin
