#pragma once
// Simulated joint sensors of a closed loop: what a controller measures of the plant's joints, as
// a real limb's encoders give it, late by a fixed delay and with Gaussian noise. The closed loop
// (closed_loop.hpp) takes a sample at each instant the sensors ask for and hands the controller
// the measurement at each control time.

#include <Simbody.h>

#include <Eigen/Core>
#include <random>
#include <vector>

#include "flatsos/plugin/model/musculoskeletal_model.hpp"
#include "flatsos/plugin/ndebug_guard.hpp"           // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

namespace flatsos::plugin {

/// What a controller measures of the joints at a control time.
struct JointMeasurement {
  double time_s = 0.0;           ///< when it was taken (the control time less the delay)
  Eigen::VectorXd q_rad;         ///< joint angles (a slider's in m), noise included
  Eigen::VectorXd qd_rad_per_s;  ///< joint speeds, noise included
  /// The plant's joint accelerations at that time, without noise: the disturbance observer's
  /// input (no sensor of this kind is modelled).
  Eigen::VectorXd qdd_rad_per_s2;
  bool allFinite() const {
    return q_rad.allFinite() && qd_rad_per_s.allFinite() && qdd_rad_per_s2.allFinite();
  }
};

struct SensorOptions {
  double angle_noise_rad = 0.0;  ///< standard deviation of each pin's angle noise (sliders: none)
  double speed_noise_rad_per_s = 0.0;  ///< standard deviation of each pin's speed noise
  double delay_s = 0.0;                ///< a measurement read at t was taken at t - delay_s
  unsigned seed = 1;                   ///< of the noise (the same seed, the same noise)
  bool ideal() const {
    return angle_noise_rad == 0.0 && speed_noise_rad_per_s == 0.0 && delay_s == 0.0;
  }
};

/// The joints of `state` exactly, into `out` (sized on the first call, reused after).
void measure_joints(const MusculoskeletalModel& plant, const SimTK::State& state,
                    JointMeasurement& out);

/// Sensors read at the control times start + k * period. A sample is kept until it is read, in
/// storage sized once: reading and sampling allocate nothing.
class JointSensors {
 public:
  /// Throws std::invalid_argument naming the option: a noise or delay that is negative or not
  /// finite.
  JointSensors(const MusculoskeletalModel& plant, const SensorOptions& options,
               double control_period_s, double start_time_s);

  /// Appends to `out` the sample times in (t_begin, t_end], ascending: each control time to come
  /// less the delay. Empty for undelayed sensors (their sample is the control time's own state).
  void sampleTimes(double t_begin, double t_end, std::vector<double>& out) const;
  /// Takes the sample at `state`'s time: the start, a sample time, or (undelayed) a control time.
  void take(const SimTK::State& state);
  /// The measurement read at control time t: the sample taken at t - delay (before the start:
  /// the start's), with fresh noise.
  const JointMeasurement& read(double t);
  const SensorOptions& options() const { return options_; }

 private:
  const MusculoskeletalModel& plant_;
  SensorOptions options_;
  double period_s_, start_s_;
  std::vector<JointMeasurement> ring_;  ///< samples not yet read, oldest at head_
  std::size_t head_ = 0, count_ = 0;
  JointMeasurement current_;  ///< the last sample read (kept while no newer one is due)
  bool have_current_ = false;
  JointMeasurement noisy_;  ///< what read() returns
  std::mt19937 random_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

}  // namespace flatsos::plugin
