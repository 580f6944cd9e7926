#pragma once
// Values a model or a posture may have but rarely does in SI units and radians: the usual trace
// of a unit mix-up (degrees for radians, centimetres or millimetres for metres). They are
// warnings, as data (one message per value, naming the field), for programs to print and store;
// what is physically impossible is rejected where it is used, as an error.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <string>
#include <vector>

#include <Eigen/Core>

#include "flatsos/plugin/model/model_description.hpp"

namespace flatsos::plugin {

/// The limits above which a value is reported (SI; all strictly "greater than").
struct PlausibilityLimits {
  double moment_arm_m = 0.2;
  double optimal_fiber_length_m = 1.0;
  double tendon_slack_length_m = 1.0;
  double musculotendon_length_m = 2.0;  ///< length at zero angles
  double body_length_m = 3.0;
  double body_mass_kg = 300.0;
  double max_isometric_force_N = 2e4;
  double gravity_m_per_s2 = 30.0;
  double joint_angle_rad = 6.283185307179586;  ///< one turn
  double slider_translation_m = 3.0;            ///< a slider's coordinate
  /// A muscle's length change per metre a slider moves (its "moment arm" there, m per m): a
  /// straight muscle changes at most 1 m per m.
  double slider_length_rate = 1.5;
};

/// Implausible values of a model description, e.g.
/// "muscles[2] 'biceps'.moment_arms_m.elbow: 3 m is above 0.2 m (centimetres given as metres?)".
std::vector<std::string> plausibility_warnings(const ModelDescription& model, const PlausibilityLimits& limits = {});

/// Joint angles beyond one turn, e.g. "target joint angles.elbow: 90 rad is beyond one turn
/// (degrees given as radians?)", and slider coordinates beyond slider_translation_m. `what`
/// names the vector. Sizes are not checked here.
std::vector<std::string> joint_angle_warnings(const ModelDescription& model, const Eigen::VectorXd& q_rad,
                                              const std::string& what, const PlausibilityLimits& limits = {});

}  // namespace flatsos::plugin
