#pragma once
// Shared test data: the paper's arm (models/arm_richter_warner.json) and the paper's open-loop initial state.
#include <memory>
#include <string>

#include <Eigen/Core>

#include "flatsos/plugin/model/musculoskeletal_model.hpp"
#include "flatsos/plugin/model/static_equilibrium.hpp"

namespace flatsos::test {

inline std::string arm_model_path() { return std::string(FLATSOS_SOURCE_DIR) + "/models/arm_richter_warner.json"; }

inline std::shared_ptr<const plugin::MusculoskeletalModel> load_arm() {
  return plugin::MusculoskeletalModel::fromFile(arm_model_path());
}

constexpr double kPi = 3.14159265358979323846;
inline double deg(double d) { return d * kPi / 180.0; }

/// The paper's initial activations at q = [0, 10 deg].
inline Eigen::VectorXd paper_a0() {
  Eigen::VectorXd a(6);
  a << 0.135, 0.040, 0.404, 0.556, 0.414, 0.068;
  return a;
}

/// The arm at q = [0, 10 deg] with the paper's activations, tendons in static equilibrium, and
/// held excitations equal to the activations.
inline SimTK::State paper_state(const plugin::MusculoskeletalModel& arm) {
  SimTK::State s = arm.defaultState();
  arm.setJointAngles(s, Eigen::Vector2d(0.0, deg(10)));
  plugin::equilibrate_tendons(arm, s, paper_a0());
  arm.setExcitations(s, paper_a0());
  return s;
}

/// A signal that is the same at every time (an excitation or an external torque).
class ConstantSignal : public plugin::ExcitationSignal {
 public:
  explicit ConstantSignal(double v) : v_(v) {}
  double value(double) const override { return v_; }

 private:
  double v_;
};

/// A signal that is `value` over [start_s, start_s + width_s) and 0 elsewhere (a torque pulse).
class TorquePulse : public plugin::ExcitationSignal {
 public:
  TorquePulse(double start_s, double width_s, double value) : start_s_(start_s), width_s_(width_s), value_(value) {}
  double value(double t) const override { return t >= start_s_ && t < start_s_ + width_s_ ? value_ : 0.0; }

 private:
  double start_s_, width_s_, value_;
};

}  // namespace flatsos::test
