// The receding-horizon controller's parts: a failed step runs the previous plan with the torque
// offset that plan was made for, not the observer's newer estimate.
#include <cmath>

#include <gtest/gtest.h>

#include "flatsos/plugin/io/model_file.hpp"
#include "rh_scenario.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
using flatsos::test::deg;

namespace {

// Calls the RH controller, then lets the test look at the state it changed.
class Probe final : public fp::Controller {
 public:
  Probe(fpl::RecedingHorizonController& rh, std::function<void(int, const SimTK::State&)> after)
      : rh_(rh), after_(std::move(after)) {}
  void control(SimTK::State& s, const fp::JointMeasurement& measured) override {
    rh_.step(s, measured);
    after_(period_++, s);
  }

 private:
  fpl::RecedingHorizonController& rh_;
  std::function<void(int, const SimTK::State&)> after_;
  int period_ = 0;
};

// The excitation at the start of the period that `plan` gives when its muscles are relieved of
// `offset`: the inverse map, computed here independently of the controller's sampling and fit.
Eigen::VectorXd excitation_at(const fpl::FlatOutputMap& flat, const fpl::PlanInUse& plan, double t,
                              const Eigen::VectorXd& offset) {
  const fpl::Jet q = plan.path.jet(t - plan.start_time_s, 5);
  fpl::TorqueJet tau = flat.torqueJet(q);
  tau.tau.col(0) -= offset;
  fpl::Jet Y = fpl::Jet::Zero(plan.alpha.size(), 3);
  Y.col(0) = plan.alpha;
  return flat.inverseFromTorque(q, tau, Y).excitation;
}
}  // namespace

TEST(RecedingHorizonController, AFailedStepRunsThePreviousPlanWithTheOffsetItWasPlannedFor) {
  flatsos::test::RecedingHorizonScenario rh;
  rh.options.disturbance_observer_gain_per_s = 20.0;
  constexpr int kFailing = 2;  // while the observer still moves
  int calls = 0;
  rh.options.planner = [&](const fpl::FlatOutputMap& f, fp::ModelWorkspace& ws, const Eigen::VectorXd& q,
                           const Eigen::VectorXd& qd, const fpl::RecedingHorizonOptions& o, fpl::RecedingHorizonStep& out) {
    if (calls++ == kFailing) {
      out.status = fpl::SolveStatus::Failed;
      out.message = "injected failure";
      return;
    }
    fpl::plan_receding_horizon_step(f, ws, q, qd, o, out);
  };
  // A constant torque the planner's model does not have: the observer's estimate moves every step.
  const auto plant = std::make_shared<const fp::MusculoskeletalModel>(
      fp::load_model_file(flatsos::test::arm_model_path()),
      std::vector<fp::ExternalJointTorque>{{0, std::make_shared<flatsos::test::ConstantSignal>(1.5)}, {1, std::make_shared<flatsos::test::ConstantSignal>(-1.0)}});
  fpl::RecedingHorizonController controller(rh.flat, rh.options, plant);
  Eigen::VectorXd applied, with_old_offset, with_new_offset;
  Probe probe(controller, [&](int period, const SimTK::State& s) {
    if (period != kFailing) return;
    const auto& rec = controller.history().back();
    applied.resize(6);
    for (int j = 0; j < 6; ++j) applied[j] = plant->muscle(j).getUnclampedExcitation(s);
    with_old_offset = excitation_at(rh.flat, rec.plan, rec.time_s, rec.plan.torque_offset_N_m);
    with_new_offset = excitation_at(rh.flat, rec.plan, rec.time_s, rec.observer_offset_N_m);
  });
  const auto run = fp::simulate_closed_loop(*plant, probe, rh.restState(plant), rh.loop(0.5, fp::IntegratorKind::CPodesBdf));
  ASSERT_TRUE(run.finite);
  const auto& h = controller.history();
  ASSERT_GT(h.size(), static_cast<std::size_t>(kFailing));
  const auto& failed = h[kFailing];
  const auto& previous = h[kFailing - 1];
  EXPECT_EQ(failed.status, fpl::SolveStatus::Failed);
  EXPECT_TRUE(failed.used_previous_plan);
  EXPECT_DOUBLE_EQ(failed.plan.start_time_s, previous.plan.start_time_s);
  EXPECT_EQ(failed.plan.torque_offset_N_m, previous.plan.torque_offset_N_m);  // the plan's own offset
  // The observer has moved on since that plan was made ...
  const double moved = (failed.observer_offset_N_m - failed.plan.torque_offset_N_m).cwiseAbs().maxCoeff();
  EXPECT_GT(moved, 0.05) << "the test needs an observer that moves";
  // ... and the muscles get the previous plan's excitations for its own offset (to the fit's
  // accuracy), which differ clearly from those for the new estimate.
  ASSERT_EQ(applied.size(), 6);
  EXPECT_LT((applied - with_old_offset).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_GT((with_new_offset - with_old_offset).cwiseAbs().maxCoeff(), 100 * 1e-5);
  EXPECT_EQ(h[kFailing + 1].status, fpl::SolveStatus::Solved);
}

TEST(RecedingHorizonController, TheObserverFollowsInSecondsNotSteps) {
  // The same disturbance over the same time moves the estimate by the same amount, whatever the
  // steps: d = (1 - exp(-g t)) w from 0, and it never passes w, even at a gain beyond 1 / period.
  fpl::DisturbanceObserver coarse(2, 20.0), fine(2, 20.0), fast(2, 400.0);
  const Eigen::Vector2d w(0.3, -0.2);
  coarse.follow(w, 0.05);
  for (int k = 0; k < 5; ++k) fine.follow(w, 0.01);
  EXPECT_LT((coarse.torqueOffset_N_m() - fine.torqueOffset_N_m()).norm(), 1e-15);
  EXPECT_LT((coarse.torqueOffset_N_m() - (1.0 - std::exp(-1.0)) * w).norm(), 1e-15);
  fast.follow(w, 0.05);
  EXPECT_LT((fast.torqueOffset_N_m() - w).norm(), 1e-8);
  EXPECT_LE(fast.torqueOffset_N_m().cwiseAbs().maxCoeff(), w.cwiseAbs().maxCoeff());
  fine.follow(Eigen::Vector2d(std::nan(""), 0.0), 0.05);  // a bad measurement leaves it alone
  EXPECT_TRUE(fine.torqueOffset_N_m().allFinite());
  EXPECT_THROW(fine.follow(w, -0.01), std::invalid_argument);
  EXPECT_THROW(fine.follow(Eigen::Vector3d::Zero(), 0.01), std::invalid_argument);
  EXPECT_THROW(fpl::DisturbanceObserver(2, -1.0), std::invalid_argument);
}

TEST(RecedingHorizonController, TheExcitationFitReproducesSmoothSamples) {
  const fpl::ExcitationFitter fitter(11, 0.05);
  EXPECT_DOUBLE_EQ(fitter.spacing_s(), 0.005);
  Eigen::VectorXd samples(11);
  // Any polynomial of degree <= 6 in the period's scaled time is reproduced to round-off.
  const auto n = [](double s) { return 0.2 + 0.3 * s - 0.5 * std::pow(s, 3) + 0.4 * std::pow(s, 6); };
  for (int i = 0; i < 11; ++i) samples[i] = n(i / 10.0);
  const auto piece = fitter.fit(samples, 1.0);
  for (double s : {0.0, 0.123, 0.5, 0.77, 1.0}) EXPECT_NEAR(piece.value(1.0 + 0.05 * s), n(s), 1e-12);
  EXPECT_DOUBLE_EQ(piece.value(0.5), piece.value(1.0));   // held before the period
  EXPECT_DOUBLE_EQ(piece.value(2.0), piece.value(1.05));  // and after it
  EXPECT_THROW(fitter.fit(Eigen::VectorXd::Zero(10), 1.0), std::invalid_argument);
  EXPECT_THROW(fpl::ExcitationFitter(1, 0.05), std::invalid_argument);
}
