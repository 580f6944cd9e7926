#pragma once
// What flatsos reads of an OpenSim model file (.osim, OpenSim 4): bodies with their mass
// properties, joints (WeldJoint, PinJoint, SliderJoint, CustomJoint) with their offset frames,
// coordinates and SpatialTransform, coordinate couplers, gravity, and every muscle's parameters
// and the bodies its path touches. Read with Simbody's XML parser. Geometry, wrapping surfaces,
// markers, contact and controllers are not read. Kinematics: opensim_kinematics.hpp.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <array>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "flatsos/plugin/io/opensim_function.hpp"
#include "flatsos/plugin/io/opensim_paths.hpp"  // OpenSimFileError

namespace flatsos::plugin {

/// A model that is read but cannot be used as asked (a coordinate it does not have, a joint
/// type or function flatsos does not evaluate, ...): the message names it.
class OpenSimModelError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct OpenSimBody {
  std::string name;
  double mass_kg = 0.0;
  Eigen::Vector3d mass_center_m = Eigen::Vector3d::Zero();  ///< in the body frame
  Eigen::Matrix3d inertia_kg_m2 = Eigen::Matrix3d::Zero();  ///< about the mass centre, body axes
};

struct OpenSimCoordinate {
  std::string name;
  std::string joint;
  double default_value = 0.0;
  std::array<double, 2> range{0.0, 0.0};  ///< rad or m
  bool locked = false;
  bool rotational = true;  ///< false: a translation (m)
};

/// One of a CustomJoint's six axes (or a PinJoint's / SliderJoint's one).
struct OpenSimTransformAxis {
  std::string name;  ///< rotation1 .. translation3
  bool rotation = true;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< unit, in the parent offset frame F
  std::vector<std::string> coordinates;              ///< 0 or 1 (more are refused when evaluated)
  OpenSimFunction function;
};

struct OpenSimJoint {
  std::string name, type;  ///< type: WeldJoint, PinJoint, SliderJoint, CustomJoint, or other (refused when used)
  std::string parent_body, child_body;  ///< "ground" or a body name
  Eigen::Isometry3d parent_offset = Eigen::Isometry3d::Identity();  ///< F in the parent body
  Eigen::Isometry3d child_offset = Eigen::Isometry3d::Identity();   ///< M in the child body
  std::vector<std::string> coordinates;
  std::vector<OpenSimTransformAxis> axes;  ///< rotations first, in order, then translations
};

/// dependent = scale * f(independent) (OpenSim's CoordinateCouplerConstraint, one independent).
struct OpenSimCoupler {
  std::string name, dependent, independent;
  OpenSimFunction function;
  double scale = 1.0;
};

struct OpenSimMuscle {
  std::string name, type;
  double max_isometric_force_N = 0.0, optimal_fiber_length_m = 0.0, tendon_slack_length_m = 0.0;
  double pennation_angle_at_optimal_rad = 0.0;
  double max_contraction_velocity_in_optimal_lengths_per_s = 10.0;
  double activation_time_constant_s = 0.01, deactivation_time_constant_s = 0.04;
  double minimum_activation = 0.01;  ///< Millard's default: the activation never falls below it
  double tendon_strain_at_one_norm_force = 0.049;  ///< Millard's default
  double passive_fiber_strain_at_one_norm_force = 0.7;  ///< Millard's default
  std::vector<std::string> path_bodies;  ///< the bodies its path points are fixed to (file order, unique)
  /// Every number the muscle's element states directly, by OpenSim's property name (its model's
  /// own properties: "FmaxTendonStrain", "Af", "fiber_damping", ...; booleans as 1 and 0:
  /// "ignore_tendon_compliance"), and those of its curve elements (tags ending in "Curve") as
  /// "<curve tag>/<property>": "ActiveForceLengthCurve/min_norm_active_fiber_length",
  /// "TendonForceLengthCurve/stiffness_at_one_norm_force", ... A property that is absent or
  /// empty (an optional curve property left unset) is not in the map.
  std::map<std::string, double> properties;
};

struct OpenSimModel {
  std::string name, credits, publications;
  Eigen::Vector3d gravity_m_per_s2 = Eigen::Vector3d(0.0, -9.80665, 0.0);
  std::vector<OpenSimBody> bodies;
  std::vector<OpenSimJoint> joints;
  std::vector<OpenSimCoordinate> coordinates;
  std::vector<OpenSimCoupler> couplers;
  std::vector<OpenSimMuscle> muscles;

  const OpenSimBody* body(const std::string& name) const;
  const OpenSimJoint* joint(const std::string& name) const;
  /// The joint whose child is `body` (nullptr for ground or a body no joint moves).
  const OpenSimJoint* jointOfChild(const std::string& body) const;
  const OpenSimCoordinate* coordinate(const std::string& name) const;
  const OpenSimMuscle* muscle(const std::string& name) const;
  /// The coupler whose dependent coordinate this is, or nullptr.
  const OpenSimCoupler* couplerOf(const std::string& dependent) const;
};

/// Reads an .osim file. Throws OpenSimFileError naming the file and the element for: a missing
/// file, a document without a Model, a body without mass properties, a joint whose frames or
/// bodies cannot be resolved, a number that does not parse, an axis of length 0, a coordinate
/// or muscle given twice.
OpenSimModel read_opensim_model(const std::string& file);
/// The same from the document's text; `source` names it in errors.
OpenSimModel parse_opensim_model(const std::string& xml, const std::string& source);

}  // namespace flatsos::plugin
