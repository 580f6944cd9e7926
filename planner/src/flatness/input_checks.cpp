#include "flatness/input_checks.hpp"

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <string>

namespace flatsos::planner::detail {

void require(const Eigen::VectorXd& v, int size, const char* what) {
  if (v.size() != size)
    throw std::invalid_argument(std::string(what) + ": expected " + std::to_string(size) +
                                " values, got " + std::to_string(v.size()));
  if (!v.allFinite())
    throw std::invalid_argument(std::string(what) + ": values must be finite (NaN or Inf given)");
}

void require_reserves(const Eigen::VectorXd& r, int m) {
  require(r, m, "reserves");
  if (r.minCoeff() < 0.0)
    throw std::invalid_argument("reserves: tendon-force reserves must be >= 0 N");
}

void require_initial_muscle_state(const FlatOutputMap& flat, const MuscleState& initial) {
  const int m = flat.numMuscles();
  require(initial.activation, m, "initial activations");
  require(initial.tendon_length_m, m, "initial tendon lengths");
  for (int j = 0; j < m; ++j) {
    const auto& mp = flat.model().muscle(j).getParameters();
    if (!(initial.activation[j] > 0.0 && initial.activation[j] <= 1.0))
      throw std::invalid_argument("initial state: activation of '" + mp.name + "' is " +
                                  std::to_string(initial.activation[j]) + ", outside (0, 1]");
    if (!(initial.tendon_length_m[j] > mp.tendon_slack_length_m))
      throw std::invalid_argument("initial state: tendon of '" + mp.name + "' is slack (" +
                                  std::to_string(initial.tendon_length_m[j]) +
                                  " m <= slack length " + std::to_string(mp.tendon_slack_length_m) +
                                  " m): flat outputs need taut tendons");
  }
}

void require_taut_tendons_possible(const plugin::MusculoskeletalModel& model,
                                   const Eigen::VectorXd& q, const char* what) {
  for (int j = 0; j < model.numMuscles(); ++j) {
    const double L = model.musculotendonLength(j, q);
    const auto& mp = model.muscle(j).getParameters();
    if (!(L > mp.tendon_slack_length_m)) {
      std::ostringstream why;
      why << what << ": the musculotendon path of '" << mp.name << "' would be " << L
          << " m long there, not longer than its tendon slack length " << mp.tendon_slack_length_m
          << " m, so its tendon cannot be taut (are the angles in radians?)";
      throw std::invalid_argument(why.str());
    }
  }
}

namespace {

// "[0, 143.2] deg" or "[-0.1, 0.1] m": a range as the user gives it.
std::string shown_range(const plugin::JointDescription& joint) {
  std::ostringstream s;
  s << "[" << joint.range_rad[0] * joint.displayPerSI() << ", "
    << joint.range_rad[1] * joint.displayPerSI() << "] " << joint.displayUnit();
  return s.str();
}

// Below this (rad or m) an angle at a range's end counts as inside: a path that starts exactly at
// a range's end evaluates there to within rounding (2e-13 deg beyond arm26's elbow at 0).
constexpr double kRangeRounding = 1e-9;

// How far q lies beyond the joint's hard range (0 inside), in SI. A joint with a limit torque has
// a soft stop: beyond its range its spring pushes back, and a task may press into it.
double beyond_range(const plugin::JointDescription& joint, double q) {
  if (joint.limit.enabled()) return 0.0;
  const double beyond = std::max({joint.range_rad[0] - q, q - joint.range_rad[1], 0.0});
  return beyond > kRangeRounding ? beyond : 0.0;
}

}  // namespace

void require_within_joint_ranges(const plugin::ModelDescription& model, const Eigen::VectorXd& q,
                                 const char* what) {
  for (int i = 0; i < static_cast<int>(model.joints.size()) && i < q.size(); ++i) {
    const plugin::JointDescription& joint = model.joints[i];
    if (!(beyond_range(joint, q[i]) > 0.0)) continue;
    std::ostringstream why;
    why << what << ": joint '" << joint.name << "' at " << q[i] * joint.displayPerSI() << " "
        << joint.displayUnit() << " is outside its range " << shown_range(joint)
        << " (the model's \"" << plugin::joint_field_names(joint.type).range << "\")";
    throw std::invalid_argument(why.str());
  }
}

std::vector<std::string> joint_range_warnings(const plugin::ModelDescription& model,
                                              const JointPath& path, double duration_s,
                                              int points) {
  std::vector<std::string> warnings;
  const int n = static_cast<int>(model.joints.size());
  Eigen::VectorXd worst = Eigen::VectorXd::Zero(n), worst_t = Eigen::VectorXd::Zero(n);
  for (int k = 0; k < points; ++k) {
    const double t = duration_s * k / std::max(points - 1, 1);
    const Eigen::VectorXd q = path.jet(t, 1).col(0);
    for (int i = 0; i < n; ++i) {
      const double beyond = beyond_range(model.joints[i], q[i]);
      if (beyond > worst[i]) worst[i] = beyond, worst_t[i] = t;
    }
  }
  for (int i = 0; i < n; ++i) {
    if (!(worst[i] > 0.0)) continue;
    const plugin::JointDescription& joint = model.joints[i];
    std::ostringstream w;
    w << "the planned path leaves the range " << shown_range(joint) << " of joint '" << joint.name
      << "' by up to " << worst[i] * joint.displayPerSI() << " " << joint.displayUnit()
      << " (at t = " << worst_t[i] << " s)";
    warnings.push_back(w.str());
  }
  return warnings;
}

}  // namespace flatsos::planner::detail
