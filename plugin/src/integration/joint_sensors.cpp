#include "flatsos/plugin/integration/joint_sensors.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "system_dynamics_lock.hpp"

namespace flatsos::plugin {

namespace {
// Two times closer than this are the same instant (sample times are sums of periods).
constexpr double kSameInstant_s = 1e-9;

void require_nonnegative(double value, const char* field) {
  if (!(value >= 0.0) || !std::isfinite(value))
    throw std::invalid_argument(std::string("sensors: ") + field +
                                " must be finite and >= 0 (got " + std::to_string(value) + ")");
}

void size_measurement(JointMeasurement& m, int joints) {
  m.q_rad.setZero(joints);
  m.qd_rad_per_s.setZero(joints);
  m.qdd_rad_per_s2.setZero(joints);
}
}  // namespace

void measure_joints(const MusculoskeletalModel& plant, const SimTK::State& state,
                    JointMeasurement& out) {
  const int n = plant.numJoints();
  if (out.q_rad.size() != n) size_measurement(out, n);
  const auto lock = detail::lock_system_dynamics(plant.system());
  plant.system().realize(state, SimTK::Stage::Acceleration);
  out.time_s = state.getTime();
  plant.jointAngles(state, out.q_rad);
  plant.jointSpeeds(state, out.qd_rad_per_s);
  for (int i = 0; i < n; ++i) out.qdd_rad_per_s2[i] = plant.joint(i).getOneUDot(state, 0);
}

JointSensors::JointSensors(const MusculoskeletalModel& plant, const SensorOptions& options,
                           double control_period_s, double start_time_s)
    : plant_(plant),
      options_(options),
      period_s_(control_period_s),
      start_s_(start_time_s),
      random_(options.seed) {
  require_nonnegative(options.angle_noise_rad, "angle noise");
  require_nonnegative(options.speed_noise_rad_per_s, "speed noise");
  require_nonnegative(options.delay_s, "measurement delay");
  if (!(control_period_s > 0.0) || !std::isfinite(control_period_s))
    throw std::invalid_argument("sensors: the control period must be > 0 s");
  // Samples in flight: those taken within one delay before a read, and the one being read.
  ring_.resize(static_cast<std::size_t>(std::ceil(options.delay_s / control_period_s)) + 2);
  for (auto& m : ring_) size_measurement(m, plant.numJoints());
  size_measurement(current_, plant.numJoints());
  size_measurement(noisy_, plant.numJoints());
}

void JointSensors::sampleTimes(double t_begin, double t_end, std::vector<double>& out) const {
  if (options_.delay_s == 0.0) return;
  const double first = std::floor((t_begin + options_.delay_s - start_s_) / period_s_);
  const double last = std::ceil((t_end + options_.delay_s - start_s_) / period_s_);
  for (double k = std::max(first, 0.0); k <= last; k += 1.0) {
    double t = start_s_ + k * period_s_ - options_.delay_s;
    if (t <= start_s_ + kSameInstant_s || t <= t_begin + kSameInstant_s ||
        t > t_end + kSameInstant_s)
      continue;
    out.push_back(std::min(t, t_end));
  }
}

void JointSensors::take(const SimTK::State& state) {
  if (count_ == ring_.size())
    head_ = (head_ + 1) % ring_.size(), --count_;  // the oldest, never read
  measure_joints(plant_, state, ring_[(head_ + count_) % ring_.size()]);
  ++count_;
}

const JointMeasurement& JointSensors::read(double t) {
  // The newest sample taken at or before t - delay; the start's stands for the time before it.
  const double taken_by = t - options_.delay_s + kSameInstant_s;
  while (count_ > 0 && (!have_current_ || ring_[head_].time_s <= taken_by)) {
    current_ = ring_[head_];  // same sizes: no allocation
    head_ = (head_ + 1) % ring_.size(), --count_;
    have_current_ = true;
  }
  noisy_ = current_;
  for (Eigen::Index i = 0; i < noisy_.q_rad.size(); ++i) {
    if (plant_.description().joints[static_cast<std::size_t>(i)].isSlider()) continue;
    noisy_.q_rad[i] += options_.angle_noise_rad * normal_(random_);
    noisy_.qd_rad_per_s[i] += options_.speed_noise_rad_per_s * normal_(random_);
  }
  return noisy_;
}

}  // namespace flatsos::plugin
