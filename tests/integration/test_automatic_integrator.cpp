// The automatic integrator (stepper.hpp, resolve_integrator): the explicit Runge-Kutta-Merson
// method unless the muscles are stiff at the start, then CPodes' BDF. The stiffness estimate is
// checked against the explicit method's own step count on the stiff model, and both choices
// against what they choose.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>

#include "../plugin/arm_fixture.hpp"
#include "arm26_transfer.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"

namespace fp = flatsos::plugin;

namespace {

using flatsos::test::Arm26Transfer;

// arm26 at rest at q = 0 with 10 N reserves (its muscles near their floor activation), its
// muscles as downloaded (Thelen) or as Moco replaces them (DeGroote-Fregly 2016).
Arm26Transfer arm26_at_rest(bool degroote) {
  fp::OpenSimFileOptions file;
  file.degroote_fregly2016_muscles = degroote;
  return flatsos::test::arm26_transfer(file);
}

fp::SimulationResult simulate(const Arm26Transfer& a, double duration_s, fp::IntegratorKind kind) {
  fp::SimulationOptions o;
  o.duration_s = duration_s;
  o.integrator = kind;
  o.accuracy = 1e-10;
  o.report_interval_s = duration_s;
  return fp::simulate(*a.model, a.rest, o);
}

}  // namespace

TEST(AutomaticIntegrator, IsNamedAutoAndResolvedBeforeAStepperIsMade) {
  EXPECT_EQ(fp::integrator_from_name("auto"), fp::IntegratorKind::Automatic);
  EXPECT_STREQ(fp::integrator_name(fp::IntegratorKind::Automatic), "auto");
  const auto arm = flatsos::test::load_arm();
  EXPECT_THROW(fp::make_stepper(*arm, fp::IntegratorKind::Automatic, 1e-8), std::invalid_argument);
  for (auto kind : {fp::IntegratorKind::RungeKuttaMerson, fp::IntegratorKind::CPodesBdf,
                    fp::IntegratorKind::MuscleRosenbrock})
    EXPECT_EQ(fp::resolve_integrator(*arm, arm->defaultState(), 1.0, kind), kind);
}

// DeGroote-Fregly muscles at rest on arm26: the biceps' tendon time scale is about 1e-6 s. The
// estimate says the explicit method needs more than kStiffExplicitSteps per run; the explicit
// method's own steps over 10 ms agree with the estimate's rate within a factor of 2, and the
// automatic choice (BDF) ends where the explicit method does, in a hundredth of its steps.
TEST(AutomaticIntegrator, ChoosesBdfWhereTheMusclesAreStiffAndTheEstimateMatchesTheExplicitSteps) {
  const Arm26Transfer a = arm26_at_rest(true);
  EXPECT_EQ(fp::resolve_integrator(*a.model, a.rest, 1.0, fp::IntegratorKind::Automatic),
            fp::IntegratorKind::CPodesBdf);
  // 10 ms is below the threshold's duration: the explicit method is chosen there, and its steps
  // measure the stiffness the estimate predicts (kStiffExplicitSteps per threshold duration).
  const double threshold_s = [&] {
    double lo = 0.0, hi = 1.0;
    for (int i = 0; i < 50; ++i) {
      const double mid = 0.5 * (lo + hi);
      (fp::resolve_integrator(*a.model, a.rest, mid, fp::IntegratorKind::Automatic) ==
               fp::IntegratorKind::CPodesBdf
           ? hi
           : lo) = mid;
    }
    return hi;
  }();
  ASSERT_GT(threshold_s, 0.01);
  const double predicted_steps_per_s = fp::kStiffExplicitSteps / threshold_s;
  const fp::SimulationResult rkm = simulate(a, 0.01, fp::IntegratorKind::Automatic);
  ASSERT_TRUE(rkm.completed()) << rkm.message;
  EXPECT_EQ(rkm.integrator, fp::IntegratorKind::RungeKuttaMerson);
  const double measured_steps_per_s = static_cast<double>(rkm.integrator_steps) / 0.01;
  EXPECT_GT(measured_steps_per_s, 0.5 * predicted_steps_per_s);
  EXPECT_LT(measured_steps_per_s, 2.0 * predicted_steps_per_s);

  const fp::SimulationResult bdf = simulate(a, 0.01, fp::IntegratorKind::CPodesBdf);
  ASSERT_TRUE(bdf.completed()) << bdf.message;
  EXPECT_LT(bdf.integrator_steps, rkm.integrator_steps / 100);
  const auto &y_rkm = rkm.final_state.getY(), &y_bdf = bdf.final_state.getY();
  for (int i = 0; i < y_rkm.size(); ++i)
    EXPECT_NEAR(y_bdf[i], y_rkm[i], 1e-6 * (1.0 + std::abs(y_rkm[i]))) << "state " << i;
  std::cout << "arm26 with DeGroote-Fregly muscles at rest: explicit steps predicted "
            << predicted_steps_per_s << " per s, taken " << measured_steps_per_s << " per s; BDF "
            << bdf.integrator_steps << " steps in 10 ms\n";
}

// Thelen's muscles at the same rest are not stiff: the explicit method stays, as do the paper's
// arm's runs.
TEST(AutomaticIntegrator, KeepsTheExplicitMethodWhereTheMusclesAreNotStiff) {
  const Arm26Transfer a = arm26_at_rest(false);
  const fp::SimulationResult run = simulate(a, 1.0, fp::IntegratorKind::Automatic);
  ASSERT_TRUE(run.completed()) << run.message;
  EXPECT_EQ(run.integrator, fp::IntegratorKind::RungeKuttaMerson);
  EXPECT_LT(run.integrator_steps, fp::kStiffExplicitSteps);
  const auto arm = flatsos::test::load_arm();
  EXPECT_EQ(fp::resolve_integrator(*arm, arm->defaultState(), 3.0, fp::IntegratorKind::Automatic),
            fp::IntegratorKind::RungeKuttaMerson);
}
