// The closed loop as a real limb runs it (issue: a controller to trust in real time): joint
// sensors that are late and noisy, plans that miss their compute deadline, measurements that are
// not finite, and set points that change, each counted and never reported as success when the
// task failed.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "flatsos/plugin/force/excitation_signal.hpp"
#include "flatsos/plugin/integration/joint_sensors.hpp"
#include "rh_scenario.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
using flatsos::test::deg;

namespace {

// Leaves every muscle unexcited (the arm falls from rest) and keeps what it measured.
class Recorder final : public fp::Controller {
 public:
  explicit Recorder(const fp::MusculoskeletalModel& plant) : plant_(plant) {}
  void control(SimTK::State& state, const fp::JointMeasurement& measured) override {
    for (int j = 0; j < plant_.numMuscles(); ++j)
      plant_.muscle(j).setExcitationPolynomial(state, fp::ExcitationPolynomial::constant(0.0));
    control_times.push_back(state.getTime());
    measurements.push_back(measured);
  }
  std::vector<double> control_times;
  std::vector<fp::JointMeasurement> measurements;

 private:
  const fp::MusculoskeletalModel& plant_;
};

// The state table's row at time t (reports every 10 ms); fails the test when there is none.
const std::vector<double>* row_at(const fp::StoTable& table, double t) {
  for (const auto& row : table.rows)
    if (std::abs(row[0] - t) < 1e-9) return &row;
  return nullptr;
}

}  // namespace

TEST(JointSensors, ADelayedMeasurementIsThePlantAsItWasThatLongBefore) {
  flatsos::test::RecedingHorizonScenario rh;
  for (const double delay_s : {0.01, 0.12}) {  // within a period, and over two periods
    auto loop = rh.loop(0.5, fp::IntegratorKind::MuscleRosenbrock, 1e-5);
    loop.control_period_s = 0.05;
    loop.reports_per_period = 5;  // rows every 10 ms: each sample time is a row
    loop.sensors.delay_s = delay_s;
    Recorder recorder(*rh.model);
    const auto run = fp::simulate_closed_loop(*rh.model, recorder, rh.restState(), loop);
    ASSERT_TRUE(run.finite);
    ASSERT_EQ(recorder.measurements.size(), 10u);
    for (std::size_t k = 0; k < recorder.measurements.size(); ++k) {
      const double taken =
          std::max(0.0, recorder.control_times[k] - delay_s);  // the start's before it
      const auto* row = row_at(run.states, taken);
      ASSERT_NE(row, nullptr) << taken;
      const auto& m = recorder.measurements[k];
      EXPECT_NEAR(m.time_s, taken, 1e-12);
      for (int j = 0; j < 2; ++j) {
        EXPECT_NEAR(m.q_rad[j], (*row)[1 + 2 * j], 1e-12) << "delay " << delay_s << " step " << k;
        EXPECT_NEAR(m.qd_rad_per_s[j], (*row)[2 + 2 * j], 1e-12)
            << "delay " << delay_s << " step " << k;
      }
    }
    // The arm fell: a delay that read the control time's own state would differ by far more.
    const auto& last = recorder.measurements.back();
    EXPECT_GT(std::abs(last.q_rad[0] - (*row_at(run.states, recorder.control_times.back()))[1]),
              1e-4);
  }
}

// Sensors only look: a delay whose sample times fall on the report times leaves the simulation
// exactly as it was without them (the same integrator steps, to the bit).
TEST(JointSensors, SamplingOnTheReportTimesLeavesTheSimulationUnchanged) {
  flatsos::test::RecedingHorizonScenario rh;
  std::vector<fp::ClosedLoopResult> runs;
  for (const double delay_s : {0.0, 0.01, 0.03}) {
    auto loop = rh.loop(0.5, fp::IntegratorKind::MuscleRosenbrock, 1e-5);
    loop.control_period_s = 0.05;
    loop.reports_per_period = 5;
    loop.sensors.delay_s = delay_s;
    Recorder recorder(*rh.model);
    runs.push_back(fp::simulate_closed_loop(*rh.model, recorder, rh.restState(), loop));
  }
  for (std::size_t r = 1; r < runs.size(); ++r) {
    EXPECT_EQ(runs[r].integrator_steps, runs[0].integrator_steps);
    ASSERT_EQ(runs[r].states.rows.size(), runs[0].states.rows.size());
    for (std::size_t i = 0; i < runs[0].states.rows.size(); ++i)
      EXPECT_EQ(runs[r].states.rows[i], runs[0].states.rows[i]) << i;
  }
}

TEST(JointSensors, NoiseHasTheGivenSpreadNoBiasAndTheSameSeedGivesTheSameNoise) {
  flatsos::test::RecedingHorizonScenario rh;
  const SimTK::State s = rh.restState();
  fp::SensorOptions o;
  o.angle_noise_rad = deg(0.2);
  o.speed_noise_rad_per_s = deg(2.0);
  o.seed = 7;
  const Eigen::VectorXd q = rh.model->jointAngles(s);
  auto spread = [&](unsigned seed, std::vector<double>* first) {
    fp::SensorOptions with_seed = o;
    with_seed.seed = seed;
    fp::JointSensors sensors(*rh.model, with_seed, 0.05, s.getTime());
    sensors.take(s);
    const int reads = 4000;
    Eigen::Vector2d sum_q = Eigen::Vector2d::Zero(), sum_q2 = sum_q, sum_qd2 = sum_q;
    for (int k = 0; k < reads; ++k) {
      const auto& m = sensors.read(s.getTime());
      const Eigen::VectorXd e = m.q_rad - q;
      if (first && k < 3) first->push_back(e[0]);
      sum_q += e, sum_q2 += e.cwiseProduct(e),
          sum_qd2 += m.qd_rad_per_s.cwiseProduct(m.qd_rad_per_s);
    }
    return std::array<Eigen::Vector2d, 3>{sum_q / reads, (sum_q2 / reads).cwiseSqrt(),
                                          (sum_qd2 / reads).cwiseSqrt()};
  };
  std::vector<double> a, b, c;
  const auto stats = spread(7, &a);
  for (int j = 0; j < 2; ++j) {
    EXPECT_LT(std::abs(stats[0][j]),
              4.0 * deg(0.2) / std::sqrt(4000.0));  // mean: 4 standard errors
    EXPECT_NEAR(stats[1][j], deg(0.2), 0.05 * deg(0.2));
    EXPECT_NEAR(stats[2][j], deg(2.0),
                0.05 * deg(2.0));  // at rest: the speed's spread is the noise's
  }
  spread(7, &b);
  spread(8, &c);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

TEST(JointSensors, RefusesANegativeOrNonFiniteNoiseOrDelayNamingIt) {
  flatsos::test::RecedingHorizonScenario rh;
  fp::SensorOptions o;
  o.delay_s = -0.01;
  try {
    fp::JointSensors(*rh.model, o, 0.05, 0.0);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("measurement delay must be finite and >= 0"),
              std::string::npos)
        << e.what();
  }
  o.delay_s = 0.0;
  o.speed_noise_rad_per_s = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(fp::JointSensors(*rh.model, o, 0.05, 0.0), std::invalid_argument);
}

// The paper's arm with the default observer, measured with 0.2 deg and 2 deg/s of noise, 10 ms
// late: it settles within 1 deg and holds there (RMS <= 0.5 deg after settling).
TEST(RealTimeLoop, NoisyLateMeasurementsStillSettleAndHold) {
  flatsos::test::RecedingHorizonScenario rh;
  rh.options.disturbance_observer_gain_per_s = 40.0;  // the product's default
  auto loop = rh.loop(3.0, fp::IntegratorKind::MuscleRosenbrock, 1e-5);
  loop.sensors.angle_noise_rad = deg(0.2);
  loop.sensors.speed_noise_rad_per_s = deg(2.0);
  loop.sensors.delay_s = 0.01;
  const auto outcome = rh.run(loop);
  ASSERT_TRUE(outcome.run.success()) << outcome.run.failures.front();
  const double settled = outcome.run.settling_time_s;
  ASSERT_GE(settled, 0.0);
  double sum = 0.0;
  int rows = 0;
  for (const auto& row : outcome.run.loop.states.rows) {
    if (row[0] < settled) continue;
    for (int j = 0; j < 2; ++j) sum += std::pow(row[1 + 2 * j] - deg(80), 2);
    rows += 2;
  }
  const double rms_deg = std::sqrt(sum / rows) / deg(1);
  EXPECT_LE(rms_deg, 0.5);
  EXPECT_GT(rms_deg, 0.0);
  RecordProperty("settling_time_s", std::to_string(settled));
  RecordProperty("rms_after_settling_deg", std::to_string(rms_deg));
}

// One step in ten, at random, misses its deadline: the previous plan's tail runs, the misses are
// counted, and the arm still reaches its target.
TEST(RealTimeLoop, InjectedDeadlineMissesFallBackOnThePreviousPlanAndAreCounted) {
  flatsos::test::RecedingHorizonScenario rh;
  rh.options.deadline.injected_miss_fraction = 0.1;
  rh.options.deadline.seed = 3;
  const auto outcome = rh.run(rh.loop(2.0, fp::IntegratorKind::MuscleRosenbrock, 1e-5));
  const auto& controller = *outcome.controller;
  const auto& faults = controller.faults();
  int missed = 0, fell_back = 0;
  for (const auto& rec : controller.history()) {
    missed += rec.deadline_missed;
    fell_back += rec.deadline_missed && rec.used_previous_plan;
  }
  EXPECT_GT(missed, 0);
  EXPECT_EQ(faults.deadline_misses, missed);
  EXPECT_EQ(faults.fallbacks, fell_back + 0);
  EXPECT_GE(faults.longest_miss_run, 1);
  EXPECT_EQ(controller.planFailures(), 0);  // a late plan is not a failed one
  EXPECT_TRUE(outcome.run.success()) << outcome.run.failures.front();
  EXPECT_LT(outcome.final_error_deg, 1.0);
}

// A deadline no plan can meet: no plan ever runs, the arm never gets there, and the run says
// the task failed and why.
TEST(RealTimeLoop, ADeadlineNoPlanMeetsFailsTheTaskAndSaysSo) {
  flatsos::test::RecedingHorizonScenario rh;
  rh.options.deadline.deadline_s = 1e-9;
  const auto outcome = rh.run(rh.loop(1.0, fp::IntegratorKind::MuscleRosenbrock, 1e-5));
  const auto& faults = outcome.controller->faults();
  EXPECT_EQ(faults.deadline_misses, outcome.controller->steps());
  EXPECT_EQ(faults.steps_without_plan, outcome.controller->steps());
  EXPECT_EQ(faults.longest_miss_run, outcome.controller->steps());
  ASSERT_FALSE(outcome.run.success());
  bool named = false;
  for (const auto& f : outcome.run.failures)
    named = named || f.find("missed their compute deadline") != std::string::npos;
  EXPECT_TRUE(named);
}

// Corrupts one measurement with NaN: the controller holds the last valid one and counts it.
class Corrupting final : public fp::Controller {
 public:
  explicit Corrupting(fpl::RecedingHorizonController& rh) : rh_(rh) {}
  void control(SimTK::State& state, const fp::JointMeasurement& measured) override {
    fp::JointMeasurement m = measured;
    if (step_++ == 6) m.qd_rad_per_s[1] = std::numeric_limits<double>::quiet_NaN();
    rh_.control(state, m);
  }

 private:
  fpl::RecedingHorizonController& rh_;
  int step_ = 0;
};

TEST(RealTimeLoop, ANonFiniteMeasurementIsHeldAndCountedNotPlannedFrom) {
  flatsos::test::RecedingHorizonScenario rh;
  fpl::RecedingHorizonController controller(rh.flat, rh.options);
  Corrupting corrupting(controller);
  auto loop = rh.loop(2.0, fp::IntegratorKind::MuscleRosenbrock, 1e-5);
  loop.control_period_s = rh.options.control_period_s;
  const auto run = fp::simulate_closed_loop(*rh.model, corrupting, rh.restState(), loop);
  ASSERT_TRUE(run.finite);
  EXPECT_EQ(controller.faults().non_finite_measurements, 1);
  EXPECT_TRUE(controller.history()[6].measurement_held);
  EXPECT_EQ(controller.history()[6].status, fpl::SolveStatus::Solved);
  EXPECT_EQ(controller.planFailures(), 0);
  const Eigen::VectorXd q = rh.model->jointAngles(run.final_state);
  EXPECT_LT((q - rh.options.plan.target_q_rad).cwiseAbs().maxCoeff(), deg(1));
}

// A new set point at 1.5 s: each is reached and held until the next.
TEST(RealTimeLoop, ChangingSetPointsAreEachReached) {
  flatsos::test::RecedingHorizonScenario rh;
  rh.options.setpoints = {{1.5, Eigen::Vector2d(deg(40), deg(60))}};
  const auto outcome = rh.run(rh.loop(3.0, fp::IntegratorKind::MuscleRosenbrock, 1e-5));
  ASSERT_TRUE(outcome.run.success()) << outcome.run.failures.front();
  ASSERT_EQ(outcome.run.setpoint_settling_s.size(), 2u);
  EXPECT_GE(outcome.run.setpoint_settling_s[0], 0.0);
  EXPECT_GE(outcome.run.setpoint_settling_s[1], 0.0);
  const Eigen::VectorXd q = rh.model->jointAngles(outcome.run.loop.final_state);
  EXPECT_LT((q - Eigen::Vector2d(deg(40), deg(60))).cwiseAbs().maxCoeff(), deg(1));
  EXPECT_EQ(outcome.controller->targetAt(1.49)[0], deg(80));
  EXPECT_EQ(outcome.controller->targetAt(1.5)[0], deg(40));
}

// (Targets outside a joint's range are refused by the check a set point shares with the target,
// tested in tests/planner/test_joint_ranges.cpp; the paper's arm has no ranges.)
TEST(RealTimeLoop, ASetPointNotFiniteOfTheWrongSizeOrOutOfOrderIsRefusedNamingIt) {
  flatsos::test::RecedingHorizonScenario rh;
  rh.options.setpoints = {
      {1.0, Eigen::Vector2d(deg(40), deg(60))},
      {2.0, Eigen::Vector2d(std::numeric_limits<double>::quiet_NaN(), deg(60))}};
  try {
    fpl::RecedingHorizonController c(rh.flat, rh.options);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("set point 2"), std::string::npos) << e.what();
  }
  rh.options.setpoints = {{1.0, Eigen::Vector3d(0.1, 0.2, 0.3)}};
  EXPECT_THROW(fpl::RecedingHorizonController(rh.flat, rh.options), std::invalid_argument);
  rh.options.setpoints = {{1.0, Eigen::Vector2d(0.5, 0.5)}, {1.0, Eigen::Vector2d(0.6, 0.6)}};
  EXPECT_THROW(fpl::RecedingHorizonController(rh.flat, rh.options), std::invalid_argument);
}
