// Model mismatch and disturbances: the RH controller plans on the nominal arm while the
// simulated arm differs (each muscle's Fmax +-20 %, segment masses +-10 %, moment arms +-10 %)
// or is pushed by a torque pulse mid-motion. The disturbance observer follows the joint torque
// the model's muscles (driven by the applied excitations) do not explain, which makes the loop
// offset free. Measured (3 s runs, CPodes BDF at 1e-8, printed by the tests), gain 40 1/s: every
// corner ends within 1.5e-5 to 4.8e-3 deg of the target and settles within 2 deg by 0.74-1.15 s;
// without the observer the corners end 3.5-32 deg off. A torque pulse is rejected to 1.4e-4 deg.
// The assertions below are these numbers with a margin of about 2.
#include <gtest/gtest.h>

#include <iomanip>
#include <iostream>

#include "../planner/scenario_fixture.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "rh_scenario.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
using flatsos::test::deg;

namespace {

struct Mismatch {
  double fmax, mass, moment_arm;
};

fp::ModelDescription mismatched(const Mismatch& m) {
  fp::ModelDescription d = fp::load_model_file(flatsos::test::arm_model_path());
  for (auto& b : d.bodies) {
    b.mass_kg *= m.mass;
    b.principal_inertia_kg_m2 *= m.mass;
  }
  for (auto& mu : d.muscles) {
    mu.parameters.max_isometric_force_N *= m.fmax;
    mu.moment_arms_m *= m.moment_arm;
  }
  return d;
}

constexpr double kGainPerSecond = 40.0;  // the default

// 3 s of the RH scenario on `plant` with the given observer gain, settling within 2 deg.
flatsos::test::RecedingHorizonScenario::Outcome run(std::shared_ptr<const fp::MusculoskeletalModel> plant, double gain_per_s) {
  flatsos::test::RecedingHorizonScenario rh;
  rh.options.disturbance_observer_gain_per_s = gain_per_s;
  auto out = rh.run(rh.loop(3.0, fp::IntegratorKind::CPodesBdf, 1e-8), std::move(plant), deg(2));
  EXPECT_TRUE(out.run.loop.finite);
  EXPECT_EQ(out.controller->planFailures(), 0);
  return out;
}

}  // namespace

TEST(ModelMismatch, EndsWithinAThousandthOfADegreeInEveryCornerWithTheObserver) {
  double worst_with = 0.0, worst_without = 0.0, slowest = 0.0;
  std::string worst_case;
  for (double fmax : {0.8, 1.2})
    for (double mass : {0.9, 1.1})
      for (double arm : {0.9, 1.1}) {
        const auto plant = std::make_shared<const fp::MusculoskeletalModel>(mismatched({fmax, mass, arm}));
        const auto with = run(plant, kGainPerSecond);
        const auto without = run(plant, 0.0);
        std::cout << "Fmax x" << fmax << " mass x" << mass << " moment arms x" << arm << ": final error "
                  << with.final_error_deg << " deg with the observer (settled within 2 deg: " << with.run.settling_time_s
                  << " s), " << without.final_error_deg << " deg without\n";
        // Measured <= 4.8e-3 deg and 0.74-1.15 s. (An observer integrating each plan's own
        // prediction error reached 8.5e-4 deg by 0.94 s here, but mistook the plans' restarts
        // for a disturbance and drove stiff-tendon models away: docs/method/receding_horizon.md.)
        EXPECT_LT(with.final_error_deg, 1e-2);
        ASSERT_GE(with.run.settling_time_s, 0.0) << "never settled within 2 deg";
        EXPECT_LT(with.run.settling_time_s, 1.3);
        slowest = std::max(slowest, with.run.settling_time_s);
        if (with.final_error_deg >= worst_with) {
          worst_with = with.final_error_deg;
          worst_case = "Fmax x" + std::to_string(fmax) + ", mass x" + std::to_string(mass) + ", arms x" + std::to_string(arm);
        }
        worst_without = std::max(worst_without, without.final_error_deg);
      }
  std::cout << "worst case with the observer: " << worst_case << ": " << worst_with << " deg, slowest settling " << slowest
            << " s (without: " << worst_without << " deg)\n";
  // The mismatch is real: the paper's controller alone ends degrees off (measured 3.5-32 deg).
  EXPECT_GT(worst_without, 3.0);
}

TEST(ModelMismatch, OnTheExactModelTheObserverSeesNoDisturbanceAndChangesNothing) {
  // The observer compares the measured motion with the model's own muscles under the applied
  // excitations, so a plan that starts from other muscle states than the plant's (each plan
  // does) is no disturbance: on the exact model d stays near 0 and the run is the paper's.
  const auto nominal = flatsos::test::load_arm();
  const auto with = run(nominal, kGainPerSecond);
  const auto without = run(nominal, 0.0);
  double largest_offset = 0.0;
  for (const auto& record : with.controller->history())
    largest_offset = std::max(largest_offset, record.observer_offset_N_m.cwiseAbs().maxCoeff());
  std::cout << "exact model: largest observer estimate " << largest_offset << " N m; final error " << with.final_error_deg
            << " deg with the observer (settled within 2 deg: " << with.run.settling_time_s << " s), "
            << without.final_error_deg << " deg without (" << without.run.settling_time_s << " s)\n";
  EXPECT_LT(largest_offset, 0.05);
  EXPECT_LT(with.final_error_deg, without.final_error_deg + 1e-4);
  ASSERT_GE(with.run.settling_time_s, 0.0);
  EXPECT_LE(with.run.settling_time_s, without.run.settling_time_s + 0.01);
}

TEST(ModelMismatch, ObserverRejectsATorquePulseFasterAndCloserThanThePapersController) {
  // The paper's controller re-plans from the measured state, so it recovers from a pulse too;
  // the observer must do better than that same run without it (measured: 1.4e-4 deg and
  // settled within 2 deg at 1.21 s with it; 1.4e-3 deg and 1.37 s without).
  const auto plant = std::make_shared<const fp::MusculoskeletalModel>(
      fp::load_model_file(flatsos::test::arm_model_path()),
      std::vector<fp::ExternalJointTorque>{{0, std::make_shared<flatsos::test::TorquePulse>(0.5, 0.1, -5.0)},  // against the shoulder
                                           {1, std::make_shared<flatsos::test::TorquePulse>(0.5, 0.1, 3.0)}});
  const auto with = run(plant, kGainPerSecond);
  const auto without = run(plant, 0.0);
  std::cout << "torque pulse: final error " << with.final_error_deg << " deg with the observer (settled " << with.run.settling_time_s
            << " s), " << without.final_error_deg << " deg without (settled " << without.run.settling_time_s << " s)\n";
  ASSERT_GE(with.run.settling_time_s, 0.0);
  ASSERT_GE(without.run.settling_time_s, 0.0);
  EXPECT_LT(with.run.settling_time_s, without.run.settling_time_s - 0.1);
  EXPECT_LT(with.final_error_deg, without.final_error_deg / 3);
  EXPECT_LT(with.final_error_deg, 5e-4);
}

TEST(ModelMismatch, ObserverConvergesToAConstantDisturbanceTorque) {
  // A constant external torque on each joint: at rest at the target the muscles must make up
  // for it, and the observer's integral state is exactly that torque (d = tau_ext).
  const Eigen::Vector2d external(1.5, -1.0);
  const auto plant = std::make_shared<const fp::MusculoskeletalModel>(
      fp::load_model_file(flatsos::test::arm_model_path()),
      std::vector<fp::ExternalJointTorque>{{0, std::make_shared<flatsos::test::ConstantSignal>(external[0])},
                                           {1, std::make_shared<flatsos::test::ConstantSignal>(external[1])}});
  const auto with = run(plant, kGainPerSecond);
  const Eigen::VectorXd d = with.controller->observer().torqueOffset_N_m();
  std::cout << std::setprecision(9) << "constant disturbance [" << external.transpose() << "] N m: observer estimate [" << d.transpose()
            << "] N m, final error " << with.final_error_deg << " deg\n";
  EXPECT_LT((d - external).cwiseAbs().maxCoeff(), 1e-2);
  EXPECT_LT(with.final_error_deg, 2e-3);
  const auto without = run(plant, 0.0);
  EXPECT_GT(without.final_error_deg, 10 * with.final_error_deg);
}
