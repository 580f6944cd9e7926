#pragma once
// A musculoskeletal model as data: bodies, pin and slider joints, gravity, muscles with constant
// moment arms, and the flat-output matrix E. Loaded from JSON (models/*.json) and validated whole:
// a bad file throws ModelFileError naming the field, never yields a half-built model.
//
// File format (SI units; see models/arm_richter_warner.json):
// {
//   "name": "...",
//   "gravity_m_per_s2": [0, -9.81, 0],
//   "bodies": [{"name", "mass_kg", "mass_center_m": [x,y,z] (body frame, origin at its joint),
//               "inertia_about_mass_center_kg_m2": Izz | [Ixx,Iyy,Izz] | [Ixx,Iyy,Izz,Ixy,Ixz,Iyz],
//               "length_m" (optional, for drawing and chains)}],
//   "joints": [{"name", "type": "pin" | "slider", "parent": "ground" | body, "child": body,
//               "location_in_parent_m": [x,y,z],
//               "axis": [x,y,z] (parent frame; a pin turns about it, optional, default [0,0,1];
//               a slider translates along it, required),
//               "coordinate": "elbow_flexion" (optional; default: the joint's name),
//               a pin: "range_rad": [lower, upper] (optional; required for the joints of a muscle
//               whose moment arms change with posture),
//               "limit_torque": {"stiffness_N_m_per_rad", "transition_rad",
//                                "damping_N_m_s_per_rad" (optional, 0)} (optional; needs
//               range_rad: a passive torque beyond the range, joint_limit.hpp);
//               a slider: the same in metres and newtons: "range_m", "limit_force":
//               {"stiffness_N_per_m", "transition_m", "damping_N_s_per_m"}}],
//   "muscle_defaults": {any MuscleParameters field except the three below} (optional),
//   "muscles": [{"name", "max_isometric_force_N", "optimal_fiber_length_m",
//                "tendon_slack_length_m",
//                either constant moment arms:
//                  "length_at_zero_angles_m",
//                  "moment_arms_m": {"<joint>": d, ...} | [d per joint, in joint order],
//                or a path that depends on posture (OpenSim's MultivariatePolynomialFunction):
//                  "path": {"coordinates": [joint or coordinate names, and held ones],
//                           "order": k, "coefficients": [...],
//                           "held_coordinates": {"<name>": value_rad} (optional)},
//                ...optional overrides of muscle_defaults, among them
//                "pennation_angle_at_optimal_rad" and "passive_fiber_strain_at_one_norm_force",
//                "muscle_model": "thelen2003" | "degroote_fregly2016" | "millard2012" | ... (the
//                laws, muscle_model.hpp; its defaults apply before the muscle's own fields),
//                and for "millard2012" (OpenSim's Millard2012EquilibriumMuscle):
//                  "fiber_damping" (0.1; below 0.001 the undamped model, then exactly 0),
//                  "maximum_pennation_angle_rad" (acos(0.1)),
//                  "millard2012_curves": {"active_force_length", "force_velocity",
//                    "fiber_force_length", "tendon_force_length", "fiber_compressive_force_length",
//                    "fiber_compressive_force_cos_pennation": each {OpenSim's property: value},
//                    e.g. "active_force_length": {"min_norm_active_fiber_length": 0.5}}
//                  (millard2012_curves.hpp; what is left out: OpenSim's defaults, optional
//                  properties all or none per curve). The strain fields then follow the curves.
//   "flat_outputs": [{"name", "weights": {"<muscle>": w, ...}}]   (optional; m - N rows; without
//                   it the planner chooses E: planner/flat_output_choice.hpp)
//   "effort_weights": "flat_outputs" | "normalized_tendon_force" | {"<muscle>": w, ...}   (optional;
//                   default: "flat_outputs" with the model's E, "normalized_tendon_force" without)
//                     (optional; every muscle listed, w >= 0, not all 0)
//   "scenarios": {"<name>": {"q0_deg": [per joint], "qd0_deg_per_s": [per joint],
//                            "activations": [per muscle], "target_deg": [per joint],
//                            "duration_s", "reserves_N": one | [per muscle]}}  (optional; every
//                 field optional: defaults for the programs, e.g. "open_loop", "receding_horizon";
//                 a slider's entries are in m and m/s, as OpenSim's inDegrees converts only
//                 rotations)
//   "provenance": {...}   (optional, free-form: where the model came from, e.g. what
//                 opensim_to_model read and approximated; kept, not interpreted)
// }
// Joints are listed parents first; joint order is generalized-coordinate order.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "flatsos/muscles/muscle_parameters.hpp"
#include "flatsos/muscles/musculotendon_path.hpp"
#include "flatsos/plugin/model/joint_limit.hpp"
#include "flatsos/plugin/model/path_geometry.hpp"

namespace flatsos::plugin {

class ModelFileError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct BodyDescription {
  std::string name;
  double mass_kg = 0.0;
  Eigen::Vector3d mass_center_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d principal_inertia_kg_m2 = Eigen::Vector3d::Zero();  ///< Ixx, Iyy, Izz about COM
  Eigen::Vector3d product_inertia_kg_m2 = Eigen::Vector3d::Zero();    ///< Ixy, Ixz, Iyz about COM
  double length_m = 0.0;  ///< 0 when not given
};

/// A pin turns its child about the axis (coordinate in rad); a slider translates it along the
/// axis without turning it (coordinate in m). The child's frame is the parent's at coordinate 0,
/// moved to location_in_parent_m.
enum class JointType { Pin, Slider };

struct JointDescription {
  std::string name;
  JointType type = JointType::Pin;
  std::string parent;  ///< "ground" or a body name
  std::string child;
  Eigen::Vector3d location_in_parent_m = Eigen::Vector3d::Zero();
  /// Unit vector, parent frame: a pin's rotation axis, a slider's direction of translation.
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  std::string coordinate;  ///< its coordinate's name (OpenSim's /jointset/<joint>/<coordinate>); empty: `name`
  /// The range of motion [lower, upper] in the coordinate's unit: rad for a pin, m for a slider
  /// (coordinateUnit()); unbounded when not given.
  std::array<double, 2> range_rad{-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  /// A passive torque beyond the range (joint_limit.hpp); off unless its stiffness is > 0, and
  /// then the range must be given. A slider's is a force: its fields read N/m, m and N s/m.
  JointLimitTorque limit;
  const std::string& coordinateName() const { return coordinate.empty() ? name : coordinate; }
  bool hasRange() const { return std::isfinite(range_rad[0]) && std::isfinite(range_rad[1]); }
  bool isSlider() const { return type == JointType::Slider; }
  /// "rad" or "m": the unit of the coordinate, its range and its limit's transition.
  const char* coordinateUnit() const { return isSlider() ? "m" : "rad"; }
  /// People read a pin's coordinate in degrees and a slider's in metres: the factor from the
  /// coordinate's SI value, and the unit's name ("deg" or "m").
  double displayPerSI() const { return isSlider() ? 1.0 : 180.0 / 3.14159265358979323846; }
  const char* displayUnit() const { return isSlider() ? "m" : "deg"; }
};

/// "pin" or "slider", as the model file names the type.
const char* joint_type_name(JointType type);

/// The model file's names of a joint's range and limit fields, which carry the units of its type.
struct JointFieldNames {
  const char* range;       ///< "range_rad" | "range_m"
  const char* limit;       ///< "limit_torque" | "limit_force"
  const char* stiffness;   ///< "stiffness_N_m_per_rad" | "stiffness_N_per_m"
  const char* transition;  ///< "transition_rad" | "transition_m"
  const char* damping;     ///< "damping_N_m_s_per_rad" | "damping_N_s_per_m"
};
const JointFieldNames& joint_field_names(JointType type);

/// A muscle path as a polynomial of coordinates, as written in the file (OpenSim's
/// MultivariatePolynomialFunction convention: see muscles/length_polynomial.hpp).
struct PolynomialPathDescription {
  /// The polynomial's arguments in order: a joint's name or its coordinate's name, or a name
  /// listed in held_coordinates_rad.
  std::vector<std::string> coordinates;
  int order = 0;
  std::vector<double> coefficients;
  std::map<std::string, double> held_coordinates_rad;  ///< arguments the model does not have
};

struct MuscleDescription {
  muscles::MuscleParameters parameters;
  /// Constant moment arms, L(q) = l0 - sum_i d_i q_i (when polynomial_path is not given).
  double length_at_zero_angles_m = 0.0;  ///< l0
  Eigen::VectorXd moment_arms_m;         ///< d_i per joint (joint order), N entries
  /// A path that depends on posture (instead of the two fields above, which stay 0 and empty).
  std::optional<PolynomialPathDescription> polynomial_path;
  /// Simulation only, never in a model file: the path's geometry to simulate with instead of the
  /// polynomial (path_geometry.hpp; set by an .osim import asked for geometry paths).
  std::shared_ptr<const PathGeometry> path_geometry;
};

struct FlatOutputDescription {
  std::string name;
  Eigen::VectorXd weights;  ///< one per muscle (muscle order)
};

/// What "minimum effort" weighs: the cost is the integral of sum_j w_j F_j (tendon forces).
struct EffortWeights {
  enum class Kind {
    Default,                ///< FlatOutputs when the model gives E, NormalizedTendonForce otherwise
    FlatOutputs,            ///< w = E^T 1: the sum of the flat outputs (the paper's; depends on E)
    NormalizedTendonForce,  ///< w_j = 1 / Fmax_j: the sum of normalized tendon forces
    PerMuscle,              ///< w as given (per_muscle)
  };
  Kind kind = Kind::Default;
  Eigen::VectorXd per_muscle;  ///< m entries >= 0, not all 0 (PerMuscle only)
};

/// Where an example motion of the model starts and ends: the programs' defaults for this model
/// (a command-line option overrides each). Empty vectors and 0 mean "not given".
struct ScenarioDescription {
  Eigen::VectorXd q0_rad, qd0_rad_per_s;  ///< N entries
  Eigen::VectorXd activations;             ///< m entries in (0, 1]
  Eigen::VectorXd target_q_rad;            ///< N entries
  double duration_s = 0.0;
  Eigen::VectorXd reserves_N;              ///< 1 (all muscles) or m entries, >= 0
};

struct ModelDescription {
  std::string name;
  Eigen::Vector3d gravity_m_per_s2 = Eigen::Vector3d(0.0, -9.81, 0.0);
  std::vector<BodyDescription> bodies;
  std::vector<JointDescription> joints;
  std::vector<MuscleDescription> muscles;
  std::vector<FlatOutputDescription> flat_outputs;  ///< empty when the file has none
  std::map<std::string, ScenarioDescription> scenarios;  ///< by name; empty when the file has none
  EffortWeights effort_weights;  ///< the file's "effort_weights" (Default when it has none)
  std::string provenance_json;   ///< the file's "provenance" object as JSON text; empty when none

  int numJoints() const { return static_cast<int>(joints.size()); }
  int numMuscles() const { return static_cast<int>(muscles.size()); }
  /// Muscle j's path over the joints (constant moment arms: an order-1 polynomial). Throws
  /// ModelFileError naming the field when the muscle's path is invalid.
  muscles::MusculotendonPath musclePath(int j) const;
  /// True when every muscle's moment arms are the same in every posture.
  bool hasConstantMomentArms() const;
  /// A (N x m): A(i, j) = d_ij, moment arm of muscle j about joint i. Throws std::logic_error
  /// when a muscle's moment arms depend on posture (see musclePath).
  Eigen::MatrixXd momentArmMatrix() const;
  /// E (p x m) from flat_outputs.
  Eigen::MatrixXd flatOutputMatrix() const;
  int muscleIndex(const std::string& name) const;  ///< -1 when absent
  int jointIndex(const std::string& name) const;   ///< -1 when absent
  /// The named scenario, or nullptr when the model has none of that name.
  const ScenarioDescription* scenario(const std::string& scenario_name) const;
};

/// Validate a description built in code (the loader calls this too).
void validate(const ModelDescription& model, const std::string& source = "model");

}  // namespace flatsos::plugin
