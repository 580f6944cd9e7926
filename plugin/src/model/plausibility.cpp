#include "flatsos/plugin/model/plausibility.hpp"

#include <cmath>
#include <sstream>
#include <vector>

namespace flatsos::plugin {

namespace {

// "<field>: <value> <unit> is above <limit> <unit> (<hint>)"
std::string above(const std::string& field, double value, double limit, const char* unit, const char* hint) {
  std::ostringstream out;
  out << field << ": " << value << ' ' << unit << " is above " << limit << ' ' << unit << " (" << hint << ")";
  return out.str();
}

std::string item(const char* list, std::size_t i, const std::string& name) {
  return std::string(list) + "[" + std::to_string(i) + "] '" + name + "'";
}

// A muscle's moment arm about joint i, or for a slider its length's rate along it (m per m, at
// most about 1 for a straight muscle), when implausibly large.
bool implausible_arm(const ModelDescription& model, std::size_t i, double arm, const PlausibilityLimits& limits) {
  return std::abs(arm) > (model.joints[i].isSlider() ? limits.slider_length_rate : limits.moment_arm_m);
}
const char* arm_unit(const ModelDescription& model, std::size_t i) { return model.joints[i].isSlider() ? "m per m" : "m"; }
double arm_limit(const ModelDescription& model, std::size_t i, const PlausibilityLimits& limits) {
  return model.joints[i].isSlider() ? limits.slider_length_rate : limits.moment_arm_m;
}

}  // namespace

std::vector<std::string> plausibility_warnings(const ModelDescription& model, const PlausibilityLimits& limits) {
  std::vector<std::string> warnings;
  const double g = model.gravity_m_per_s2.norm();
  if (g > limits.gravity_m_per_s2)
    warnings.push_back(above("gravity_m_per_s2", g, limits.gravity_m_per_s2, "m/s^2", "cm/s^2 given as m/s^2?"));
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const auto& b = model.bodies[i];
    const std::string at = item("bodies", i, b.name);
    if (b.mass_kg > limits.body_mass_kg)
      warnings.push_back(above(at + ".mass_kg", b.mass_kg, limits.body_mass_kg, "kg", "grams given as kilograms?"));
    if (b.length_m > limits.body_length_m)
      warnings.push_back(above(at + ".length_m", b.length_m, limits.body_length_m, "m", "centimetres or millimetres given as metres?"));
  }
  for (std::size_t j = 0; j < model.muscles.size(); ++j) {
    const auto& m = model.muscles[j];
    const auto& p = m.parameters;
    const std::string at = item("muscles", j, p.name);
    for (int i = 0; i < m.moment_arms_m.size() && i < model.numJoints(); ++i) {
      const auto k = static_cast<std::size_t>(i);
      if (implausible_arm(model, k, m.moment_arms_m[i], limits))
        warnings.push_back(above(at + ".moment_arms_m." + model.joints[k].name, std::abs(m.moment_arms_m[i]),
                                 arm_limit(model, k, limits), arm_unit(model, k), "centimetres given as metres?"));
    }
    if (m.polynomial_path) {
      // A path that depends on posture: judged at the middle of the joints' ranges.
      const muscles::MusculotendonPath path = model.musclePath(static_cast<int>(j));
      std::vector<double> q(static_cast<std::size_t>(model.numJoints()), 0.0), r(q.size());
      for (std::size_t i = 0; i < q.size(); ++i)
        if (model.joints[i].hasRange()) q[i] = 0.5 * (model.joints[i].range_rad[0] + model.joints[i].range_rad[1]);
      path.momentArms(q.data(), r.data());
      for (std::size_t i = 0; i < r.size(); ++i)
        if (implausible_arm(model, i, r[i], limits))
          warnings.push_back(above(at + ".path: moment arm about " + model.joints[i].name + " at mid-range", std::abs(r[i]),
                                   arm_limit(model, i, limits), arm_unit(model, i), "centimetres given as metres?"));
      const double length = path.length(q.data());
      if (length > limits.musculotendon_length_m)
        warnings.push_back(above(at + ".path: length at mid-range", length, limits.musculotendon_length_m, "m",
                                 "millimetres or centimetres given as metres?"));
    }
    if (p.optimal_fiber_length_m > limits.optimal_fiber_length_m)
      warnings.push_back(above(at + ".optimal_fiber_length_m", p.optimal_fiber_length_m, limits.optimal_fiber_length_m,
                               "m", "millimetres or centimetres given as metres?"));
    if (p.tendon_slack_length_m > limits.tendon_slack_length_m)
      warnings.push_back(above(at + ".tendon_slack_length_m", p.tendon_slack_length_m, limits.tendon_slack_length_m, "m",
                               "millimetres or centimetres given as metres?"));
    if (m.length_at_zero_angles_m > limits.musculotendon_length_m)
      warnings.push_back(above(at + ".length_at_zero_angles_m", m.length_at_zero_angles_m, limits.musculotendon_length_m,
                               "m", "millimetres or centimetres given as metres?"));
    if (p.max_isometric_force_N > limits.max_isometric_force_N)
      warnings.push_back(above(at + ".max_isometric_force_N", p.max_isometric_force_N, limits.max_isometric_force_N, "N",
                               "stronger than any human muscle"));
  }
  return warnings;
}

std::vector<std::string> joint_angle_warnings(const ModelDescription& model, const Eigen::VectorXd& q_rad,
                                              const std::string& what, const PlausibilityLimits& limits) {
  std::vector<std::string> warnings;
  for (int i = 0; i < q_rad.size() && i < model.numJoints(); ++i) {
    const JointDescription& joint = model.joints[static_cast<std::size_t>(i)];
    std::ostringstream out;
    if (!joint.isSlider() && std::abs(q_rad[i]) > limits.joint_angle_rad)
      out << what << '.' << joint.name << ": " << q_rad[i] << " rad is beyond one turn (degrees given as radians?)";
    if (joint.isSlider() && std::abs(q_rad[i]) > limits.slider_translation_m)
      out << what << '.' << joint.name << ": " << q_rad[i] << " m is beyond " << limits.slider_translation_m
          << " m along the slider (millimetres or centimetres given as metres?)";
    if (!out.str().empty()) warnings.push_back(out.str());
  }
  return warnings;
}

}  // namespace flatsos::plugin
