// The muscles' inputs reaching the plant late (issue: a controller to trust in real time): what a
// controller sets at t acts from t + delay, as the same inputs sent that much later would, and the
// receding-horizon controller still reaches its target through a stimulator's latency.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "flatsos/plugin/force/excitation_signal.hpp"
#include "flatsos/plugin/integration/actuation_delay.hpp"
#include "rh_scenario.hpp"

namespace fp = flatsos::plugin;
using flatsos::test::deg;

namespace {

constexpr double kPeriod_s = 0.05;

// Sets, at control step k, the excitation ramp from schedule[k] to schedule[k] + 0.1 over the
// period on every muscle (step k - shift's ramp, started at the control time: the schedule sent
// `shift` periods late).
class ScheduleController final : public fp::Controller {
 public:
  ScheduleController(const fp::MusculoskeletalModel& plant, std::vector<double> schedule,
                     int shift = 0)
      : plant_(plant), schedule_(std::move(schedule)), shift_(shift) {}
  void control(SimTK::State& state, const fp::JointMeasurement&) override {
    const int k = std::max(0, step_++ - shift_);
    fp::ExcitationPolynomial ramp;
    ramp.count = 2;
    ramp.coefficients[0] = schedule_.at(static_cast<std::size_t>(k));
    ramp.coefficients[1] = 0.1;
    // Sent late, a ramp starts where a delayed one would: its control time plus the delay, in the
    // same arithmetic.
    ramp.start_time_s = shift_ > 0 ? previous_time_s_ + kPeriod_s : state.getTime();
    ramp.duration_s = kPeriod_s;
    if (shift_ > 0 && step_ <= shift_) ramp = fp::ExcitationPolynomial::constant(kRest);
    previous_time_s_ = state.getTime();
    for (int j = 0; j < plant_.numMuscles(); ++j)
      plant_.muscle(j).setExcitationPolynomial(state, ramp);
  }
  static constexpr double kRest = 0.05;  // the scenario's rest excitation, in effect at the start

 private:
  const fp::MusculoskeletalModel& plant_;
  std::vector<double> schedule_;
  int shift_, step_ = 0;
  double previous_time_s_ = 0.0;
};

const std::vector<double> kSchedule{0.3, 0.1, 0.6, 0.2, 0.5, 0.05, 0.4, 0.25, 0.35, 0.15};

// The arm at rest with every muscle held at kRest: what is in effect until a command arrives.
SimTK::State start_state(const flatsos::test::RecedingHorizonScenario& rh) {
  SimTK::State s = rh.restState();
  rh.model->setExcitations(
      s, Eigen::VectorXd::Constant(rh.model->numMuscles(), ScheduleController::kRest));
  return s;
}

fp::ClosedLoopOptions schedule_loop(double actuation_delay_s) {
  auto loop =
      flatsos::test::RecedingHorizonScenario::loop(0.5, fp::IntegratorKind::MuscleRosenbrock, 1e-8);
  loop.control_period_s = kPeriod_s;
  loop.reports_per_period = 5;
  loop.actuation_delay_s = actuation_delay_s;
  return loop;
}

// The excitation in effect at t under the schedule sent `delay_s` late (before it: the rest's).
double expected_excitation(double t, double delay_s) {
  const double sent = t - delay_s;
  if (sent < 0.0) return ScheduleController::kRest;
  const auto k = static_cast<std::size_t>(std::floor(sent / kPeriod_s + 1e-9));
  const double s = std::clamp(sent / kPeriod_s - static_cast<double>(k), 0.0, 1.0);
  return kSchedule.at(std::min(k, kSchedule.size() - 1)) + 0.1 * s;
}

}  // namespace

// A delay of a whole period is the schedule sent one period later, to the bit: the same inputs
// change at the same control times.
TEST(ActuationDelay, APeriodsDelayIsTheScheduleSentAPeriodLater) {
  flatsos::test::RecedingHorizonScenario rh;
  ScheduleController late(*rh.model, kSchedule), shifted(*rh.model, kSchedule, 1);
  const auto delayed =
      fp::simulate_closed_loop(*rh.model, late, start_state(rh), schedule_loop(kPeriod_s));
  const auto sent_later =
      fp::simulate_closed_loop(*rh.model, shifted, start_state(rh), schedule_loop(0.0));
  ASSERT_TRUE(delayed.finite && sent_later.finite);
  ASSERT_EQ(delayed.states.rows.size(), sent_later.states.rows.size());
  for (std::size_t r = 0; r < delayed.states.rows.size(); ++r)
    for (std::size_t c = 0; c < delayed.states.rows[r].size(); ++c)
      ASSERT_EQ(delayed.states.rows[r][c], sent_later.states.rows[r][c])
          << "row " << r << " column " << c;
  ScheduleController on_time(*rh.model, kSchedule);
  const auto undelayed =
      fp::simulate_closed_loop(*rh.model, on_time, start_state(rh), schedule_loop(0.0));
  EXPECT_GT(std::abs(undelayed.states.rows.back()[1] - delayed.states.rows.back()[1]), 1e-4);
}

// A delay within a period: each ramp acts from its control time + delay, running as it would have
// from the control time (read back from the controls table between the arrival times).
TEST(ActuationDelay, EachCommandActsFromItsControlTimePlusTheDelayShiftedWhole) {
  flatsos::test::RecedingHorizonScenario rh;
  for (const double delay_s : {0.013, 0.087}) {  // within a period, and over one
    ScheduleController controller(*rh.model, kSchedule);
    const auto run =
        fp::simulate_closed_loop(*rh.model, controller, start_state(rh), schedule_loop(delay_s));
    ASSERT_TRUE(run.finite);
    int checked = 0;
    for (const auto& row : run.controls.rows) {
      const double t = row[0];
      const double since_arrival = std::fmod(t - delay_s + 10 * kPeriod_s, kPeriod_s);
      if (since_arrival < 1e-6 || kPeriod_s - since_arrival < 1e-6)
        continue;  // at an arrival: either
      for (std::size_t j = 1; j < row.size(); ++j)
        EXPECT_NEAR(row[j], expected_excitation(t, delay_s), 1e-12)
            << "t " << t << " delay " << delay_s;
      ++checked;
    }
    EXPECT_GT(checked, 40);
  }
}

TEST(ActuationDelay, RefusesANegativeOrNonFiniteDelayNamingIt) {
  flatsos::test::RecedingHorizonScenario rh;
  for (const double bad :
       {-0.01, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    ScheduleController controller(*rh.model, kSchedule);
    try {
      fp::simulate_closed_loop(*rh.model, controller, start_state(rh), schedule_loop(bad));
      FAIL() << "accepted an actuation delay of " << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("actuation delay"), std::string::npos) << e.what();
    }
  }
}

// The paper's arm with the default observer, its excitations 10 ms late as well as measured late
// and noisy: it still settles within 1 deg, and the delay changed the run.
TEST(ActuationDelay, TheControllerStillSettlesThroughAStimulatorsLatency) {
  flatsos::test::RecedingHorizonScenario rh;
  rh.options.disturbance_observer_gain_per_s = 40.0;  // the product's default
  auto loop = rh.loop(3.0, fp::IntegratorKind::MuscleRosenbrock, 1e-5);
  loop.sensors.angle_noise_rad = deg(0.2);
  loop.sensors.speed_noise_rad_per_s = deg(2.0);
  loop.sensors.delay_s = 0.01;
  const auto on_time = rh.run(loop);
  loop.actuation_delay_s = 0.01;
  const auto late = rh.run(loop);
  ASSERT_TRUE(late.run.success()) << late.run.failures.front();
  EXPECT_GE(late.run.settling_time_s, 0.0);
  EXPECT_LE(late.run.settling_time_s, 2.0);
  EXPECT_NE(late.run.loop.states.rows[20][1], on_time.run.loop.states.rows[20][1]);
  RecordProperty("settling_time_s", std::to_string(late.run.settling_time_s));
}
