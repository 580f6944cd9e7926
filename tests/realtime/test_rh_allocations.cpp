// The receding-horizon controller's inner loop allocates no heap memory after its first period:
// the paper's closed loop (exact SLP, disturbance observer on, a constant torque the planner's
// model does not have, so the observer and the offset path are exercised) with every control
// period's allocations counted by the process-wide counter this program links
// (allocation_counter.cpp). Timings are not asserted here; the benchmark measures them.

#include <functional>
#include <vector>

#include <gtest/gtest.h>

#include "allocation_counter.hpp"
#include "../integration/rh_scenario.hpp"
#include "flatsos/plugin/io/model_file.hpp"

namespace {

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;

// Counts the heap allocations of each control() call of the controller it wraps.
class CountingController final : public fp::Controller {
 public:
  explicit CountingController(fpl::RecedingHorizonController& rh) : rh_(rh) {}
  void control(SimTK::State& state, const fp::JointMeasurement& measured) override {
    const long before = heap_allocations();
    rh_.control(state, measured);
    per_period.push_back(heap_allocations() - before);
  }
  std::vector<long> per_period;

 private:
  fpl::RecedingHorizonController& rh_;
};

struct Counted {
  std::vector<long> per_period;
  int steps = 0, failures = 0;
  double final_error_deg = 0.0;
};

Counted run_counted(bool keep_history) {
  flatsos::test::RecedingHorizonScenario rh;
  rh.options.disturbance_observer_gain_per_s = 20.0;
  rh.options.keep_history = keep_history;
  const auto plant = std::make_shared<const fp::MusculoskeletalModel>(
      fp::load_model_file(flatsos::test::arm_model_path()),
      std::vector<fp::ExternalJointTorque>{{0, std::make_shared<flatsos::test::ConstantSignal>(1.0)}});
  fpl::RecedingHorizonController controller(rh.flat, rh.options, plant);
  CountingController counting(controller);
  auto loop = rh.loop(1.5, fp::IntegratorKind::CPodesBdf);
  loop.control_period_s = rh.options.control_period_s;
  const auto run = fp::simulate_closed_loop(*plant, counting, rh.restState(plant), loop);
  EXPECT_TRUE(run.finite);
  Counted c;
  c.per_period = counting.per_period;
  c.steps = controller.steps();
  c.failures = controller.planFailures();
  c.final_error_deg = (plant->jointAngles(run.final_state) - rh.options.plan.target_q_rad).cwiseAbs().maxCoeff() /
                      flatsos::test::deg(1);
  return c;
}

TEST(RealTime, AControlPeriodAllocatesNothingAfterTheFirst) {
  if (heap_allocations() < 0) GTEST_SKIP() << "allocations are not counted under AddressSanitizer";
  const Counted c = run_counted(/*keep_history=*/false);
  ASSERT_GE(c.steps, 30);
  EXPECT_EQ(c.failures, 0);
  EXPECT_LT(c.final_error_deg, 1.0);  // the loop did its job: the arm is at the target
  EXPECT_GT(c.per_period.front(), 0);  // the first period sizes the storage
  for (std::size_t k = 1; k < c.per_period.size(); ++k) EXPECT_EQ(c.per_period[k], 0) << "control period " << k;
}

TEST(RealTime, KeepingTheHistoryIsWhatAllocates) {
  // The counter sees allocations where there are some: each kept record copies its plan.
  if (heap_allocations() < 0) GTEST_SKIP() << "allocations are not counted under AddressSanitizer";
  const Counted c = run_counted(/*keep_history=*/true);
  long later = 0;
  for (std::size_t k = 1; k < c.per_period.size(); ++k) later += c.per_period[k];
  EXPECT_GT(later, 0);
}

}  // namespace
