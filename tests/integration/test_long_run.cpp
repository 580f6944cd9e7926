// Long runs of the closed loop (issue: a controller to trust in real time): ten minutes of
// simulated time with a new set point every 2 s, streamed instead of kept, with flat memory; a
// stop request that ends a run early and says so; and the settling times computed row by row
// agreeing with those of a kept table.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "flatsos/planner/step_time_histogram.hpp"
#include "rh_scenario.hpp"
#include "under_asan.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
using flatsos::test::deg;

namespace {

// AddressSanitizer keeps freed memory in quarantine (up to 256 MB): resident memory says nothing
// of the program's own growth there.
#if defined(FLATSOS_UNDER_ASAN)
constexpr bool kResidentMemoryMeansGrowth = false;
#else
constexpr bool kResidentMemoryMeansGrowth = true;
#endif

// Resident memory of this process, bytes (Linux: /proc/self/statm's second field, in pages).
long resident_bytes() {
  std::ifstream statm("/proc/self/statm");
  long size_pages = 0, resident_pages = 0;
  statm >> size_pages >> resident_pages;
  return resident_pages * 4096;
}

// A set point every 2 s from `from_s` on, drawn within [30, 100] deg for both joints.
std::vector<fpl::Setpoint> random_setpoints(double from_s, double to_s, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> angle(deg(30), deg(100));
  std::vector<fpl::Setpoint> out;
  for (double t = from_s; t < to_s; t += 2.0)
    out.push_back({t, Eigen::Vector2d(angle(random), angle(random))});
  return out;
}

}  // namespace

// The settling times found row by row are the ones plugin::settling_time finds in the kept table.
TEST(LongRun, SettlingTimesRowByRowAreThoseOfTheKeptTable) {
  flatsos::test::RecedingHorizonScenario rh;
  rh.options.disturbance_observer_gain_per_s = 40.0;
  rh.options.setpoints = random_setpoints(2.0, 8.0, 3);
  const auto outcome = rh.run(rh.loop(8.0, fp::IntegratorKind::MuscleRosenbrock, 1e-5));
  const auto& run = outcome.run;
  ASSERT_EQ(run.setpoint_settling_s.size(), rh.options.setpoints.size() + 1);
  for (std::size_t i = 0; i < run.setpoint_settling_s.size(); ++i) {
    const double from = i == 0 ? 0.0 : rh.options.setpoints[i - 1].time_s;
    const double to = i < rh.options.setpoints.size() ? rh.options.setpoints[i].time_s : 1e300;
    const Eigen::VectorXd& target =
        i == 0 ? rh.options.plan.target_q_rad : rh.options.setpoints[i - 1].target_q_rad;
    const double settled =
        fp::settling_time(*rh.model, run.loop.states, target, deg(1), 1e-3, from, to);
    EXPECT_EQ(run.setpoint_settling_s[i], settled < 0.0 ? -1.0 : settled - from)
        << "set point " << i;
    EXPECT_GE(run.setpoint_settling_s[i], 0.0) << "set point " << i;
  }
  EXPECT_EQ(run.settling_time_s,
            fp::settling_time(*rh.model, run.loop.states, rh.options.setpoints.back().target_q_rad,
                              deg(1), 1e-3, rh.options.setpoints.back().time_s));
}

// Ten minutes with a new set point every 2 s, no history and no tables kept: every set point
// reached, and the resident memory after the first minute grows by less than 2 MB.
TEST(LongRun, TenMinutesOfSetPointsWithFlatMemory) {
  flatsos::test::RecedingHorizonScenario rh;
  rh.options.disturbance_observer_gain_per_s = 40.0;
  rh.options.keep_history = false;
  constexpr double kDuration_s = 600.0;
  rh.options.setpoints = random_setpoints(2.0, kDuration_s, 7);
  auto loop = rh.loop(kDuration_s, fp::IntegratorKind::MuscleRosenbrock, 1e-5);
  loop.keep_tables = false;
  long rows = 0, after_first_minute = 0;
  loop.report = [&](const SimTK::State& state) {
    ++rows;
    if (after_first_minute == 0 && state.getTime() >= 60.0) after_first_minute = resident_bytes();
  };
  const auto outcome = rh.run(loop);
  const long at_end = resident_bytes();
  ASSERT_TRUE(outcome.run.success()) << outcome.run.failures.front();
  EXPECT_TRUE(outcome.run.loop.states.rows.empty());
  EXPECT_TRUE(outcome.controller->history().empty());
  EXPECT_EQ(rows, 1 + 5 * 12000);  // the start's row and 5 per period
  ASSERT_EQ(outcome.run.setpoint_settling_s.size(), rh.options.setpoints.size() + 1);
  for (const double settled : outcome.run.setpoint_settling_s) EXPECT_GE(settled, 0.0);
  const double growth_MB = static_cast<double>(at_end - after_first_minute) / 1e6;
  if (kResidentMemoryMeansGrowth) {
    EXPECT_LT(growth_MB, 2.0);
  }
  RecordProperty("memory_growth_after_first_minute_MB", std::to_string(growth_MB));
  RecordProperty("real_time_factor", std::to_string(outcome.run.loop.real_time_factor));
}

// A stop request ends the run at the next control time: the tables hold the run up to there, and
// the run is no success and says why.
TEST(LongRun, AStopRequestEndsTheRunAtTheNextControlTimeAndSaysSo) {
  flatsos::test::RecedingHorizonScenario rh;
  auto loop = rh.loop(3.0, fp::IntegratorKind::MuscleRosenbrock, 1e-5);
  std::atomic<bool> stop{false};
  loop.stop = &stop;
  loop.report = [&](const SimTK::State& state) {
    if (state.getTime() >= 1.01) stop = true;
  };
  const auto outcome = rh.run(loop);
  const auto& run = outcome.run;
  EXPECT_TRUE(run.loop.stopped);
  EXPECT_TRUE(run.loop.finite);
  EXPECT_NEAR(run.loop.final_state.getTime(), 1.05, 1e-9);
  EXPECT_NEAR(run.loop.states.rows.back()[0], 1.05, 1e-9);
  ASSERT_FALSE(run.success());
  EXPECT_NE(run.failures.front().find("stop"), std::string::npos) << run.failures.front();
}

// The step-time histogram's quantiles are the exact order statistics to within half a bin.
TEST(StepTimeHistogram, QuantilesAreTheOrderStatisticsToWithinHalfABin) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> exponent(-6.0, -1.0);
  fpl::StepTimeHistogram histogram;
  EXPECT_EQ(histogram.quantile(0.5), 0.0);
  std::vector<double> times;
  for (int i = 0; i < 20001; ++i) {
    times.push_back(std::pow(10.0, exponent(random)));
    histogram.add(times.back());
  }
  std::sort(times.begin(), times.end());
  const double half_bin = std::pow(fpl::StepTimeHistogram::kHighest_s / fpl::StepTimeHistogram::kLowest_s,
                                   0.5 / fpl::StepTimeHistogram::kBins);
  for (const double fraction : {0.01, 0.5, 0.9, 0.99, 0.999, 1.0}) {
    const double exact = times[static_cast<std::size_t>(std::ceil(fraction * static_cast<double>(times.size()))) - 1];
    const double ratio = histogram.quantile(fraction) / exact;
    EXPECT_LE(ratio, half_bin * (1 + 1e-12)) << fraction;
    EXPECT_GE(ratio, 1 / half_bin / (1 + 1e-12)) << fraction;
  }
  histogram.add(1e3);  // beyond the last bin: counted there
  histogram.add(0.0);  // below the first
  EXPECT_EQ(histogram.count(), 20003);
  EXPECT_GT(histogram.quantile(1.0), 90.0);
  EXPECT_LT(histogram.quantile(1e-9), 1.1e-7);
}

// A duration of more control periods than an int counts is refused, naming it (it overflowed).
TEST(LongRun, ADurationOfMoreThanABillionPeriodsIsRefused) {
  flatsos::test::RecedingHorizonScenario rh;
  auto loop = rh.loop(1e12, fp::IntegratorKind::MuscleRosenbrock, 1e-5);
  try {
    rh.run(loop);
    FAIL() << "accepted a duration of 1e12 s";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("control periods"), std::string::npos) << e.what();
  }
}

// Without the history a failed run still says when its first plan failed and why, as with it.
TEST(LongRun, TheFirstFailedPlanIsNamedWithoutTheHistoryToo) {
  std::vector<std::string> sentences;
  for (const bool history : {true, false}) {
    flatsos::test::RecedingHorizonScenario rh;
    rh.options.plan.target_q_rad = Eigen::Vector2d(deg(80), deg(170));  // beyond the muscles
    rh.options.keep_history = history;
    const auto outcome = rh.run(rh.loop(0.3, fp::IntegratorKind::MuscleRosenbrock, 1e-5));
    ASSERT_GT(outcome.controller->planFailures(), 0);
    EXPECT_EQ(outcome.controller->firstFailureTime(), 0.0);
    EXPECT_FALSE(outcome.controller->firstFailureMessage().empty());
    sentences.push_back(fpl::plan_failures_sentence(*outcome.controller));
  }
  EXPECT_NE(sentences[1].find("the first at t = 0 s: "), std::string::npos) << sentences[1];
  EXPECT_EQ(sentences[0], sentences[1]);
}
