// The Stepper contract, the same for every integrator: report times strictly ascending in
// (now, t_end], a callback when there are any, one report per time with the state at exactly
// that time, no target before now. Regression: RKM and BDF used to call an unset callback
// (std::bad_function_call), the Rosenbrock method skipped it, and unsorted times were accepted
// with states coming back for the wrong times.
#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "arm_fixture.hpp"
#include "flatsos/plugin/integration/stepper.hpp"

namespace fp = flatsos::plugin;
using flatsos::test::deg;

namespace {

void expect_rejected(fp::Stepper& stepper, double t_end, const std::vector<double>& times, bool with_report,
                     const std::string& why) {
  const double before = stepper.state().getTime();
  int calls = 0;
  const fp::Stepper::Report report = with_report ? fp::Stepper::Report([&](const SimTK::State&) { ++calls; }) : nullptr;
  try {
    stepper.advanceTo(t_end, times, report);
    ADD_FAILURE() << "accepted: " << why;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
  }
  EXPECT_EQ(calls, 0);
  EXPECT_EQ(stepper.state().getTime(), before) << "moved before refusing";
}

class StepperContract : public ::testing::TestWithParam<fp::IntegratorKind> {};

}  // namespace

TEST_P(StepperContract, BadTimesAreRefusedBeforeAnythingMoves) {
  const auto arm = flatsos::test::load_arm();
  const auto stepper = fp::make_stepper(*arm, GetParam(), 1e-8);
  stepper->initialize(flatsos::test::paper_state(*arm));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expect_rejected(*stepper, 0.1, {0.02, 0.05}, false, "no report callback");
  expect_rejected(*stepper, 0.1, {0.05, 0.02}, true, "report time 1 (0.02");
  expect_rejected(*stepper, 0.1, {0.02, 0.02}, true, "not after the one before it");
  expect_rejected(*stepper, 0.1, {0.0, 0.05}, true, "not after the current time");
  expect_rejected(*stepper, 0.1, {0.05, 0.2}, true, "lies after the target time");
  expect_rejected(*stepper, 0.1, {nan}, true, "report time 0 is not finite");
  expect_rejected(*stepper, nan, {}, true, "target time is not finite");
  ASSERT_TRUE(stepper->advanceTo(0.05));
  EXPECT_THROW(stepper->advanceTo(0.01), std::invalid_argument);  // before now
  EXPECT_TRUE(stepper->advanceTo(0.05));                          // now: nothing to do
  EXPECT_DOUBLE_EQ(stepper->state().getTime(), 0.05);
  EXPECT_TRUE(stepper->advanceTo(0.1, {}, nullptr));              // no reports, no callback needed
}

TEST_P(StepperContract, EveryReportTimeIsReportedOnceWithItsState) {
  const auto arm = flatsos::test::load_arm();
  const SimTK::State start = flatsos::test::paper_state(*arm);
  const std::vector<double> times = {0.013, 0.05, 0.0501, 0.2, 0.3};
  std::vector<double> reported, q_elbow;
  const auto stepper = fp::make_stepper(*arm, GetParam(), 1e-9);
  stepper->initialize(start);
  ASSERT_TRUE(stepper->advanceTo(0.3, times, [&](const SimTK::State& s) {
    reported.push_back(s.getTime());
    q_elbow.push_back(arm->jointAngles(s)[1]);
  }));
  ASSERT_EQ(reported.size(), times.size());
  for (std::size_t i = 0; i < times.size(); ++i) EXPECT_DOUBLE_EQ(reported[i], times[i]);
  // The same states as an RKM run cut at the report times (tolerance: the accuracy, 1e-9,
  // times the elbow's swing, with a margin of 100 for error accumulated over the run).
  const auto reference = fp::make_stepper(*arm, fp::IntegratorKind::RungeKuttaMerson, 1e-11);
  reference->initialize(start);
  for (std::size_t i = 0; i < times.size(); ++i) {
    ASSERT_TRUE(reference->advanceTo(times[i]));
    EXPECT_NEAR(q_elbow[i], arm->jointAngles(reference->state())[1], 1e-7) << "at " << times[i];
  }
}

INSTANTIATE_TEST_SUITE_P(AllIntegrators, StepperContract,
                         ::testing::Values(fp::IntegratorKind::RungeKuttaMerson, fp::IntegratorKind::CPodesBdf,
                                           fp::IntegratorKind::MuscleRosenbrock),
                         [](const auto& param_info) { return std::string(fp::integrator_name(param_info.param)); });
