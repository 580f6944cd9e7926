// Model mismatch and disturbances: the RH controller plans on the nominal arm while the
// simulated arm differs (each muscle's Fmax +-20 %, segment masses +-10 %, moment arms +-10 %)
// or is pushed by a torque pulse mid-motion. The disturbance observer integrates the plan's
// prediction error (joint torque the plant did not deliver), which makes the loop offset free.
// Measured (3 s runs, CPodes BDF at 1e-8, printed by the tests), gain 20 1/s: every corner ends
// within 6.8e-5 to 8.5e-4 deg of the target and settles within 2 deg by 0.65-0.94 s; without the
// observer the corners end 3.5-32 deg off. A torque pulse is rejected to 2.2e-4 deg. The
// assertions below are these numbers with a margin of about 2.
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

class TorquePulse : public fp::ExcitationSignal {
 public:
  TorquePulse(double start, double width, double torque) : start_(start), width_(width), torque_(torque) {}
  double value(double t) const override { return t >= start_ && t < start_ + width_ ? torque_ : 0.0; }

 private:
  double start_, width_, torque_;
};

constexpr double kGainPerSecond = 20.0;  // 1 per 0.05 s period

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
        EXPECT_LT(with.final_error_deg, 2e-3);  // measured <= 8.5e-4
        ASSERT_GE(with.run.settling_time_s, 0.0) << "never settled within 2 deg";
        EXPECT_LT(with.run.settling_time_s, 1.2);  // measured 0.65-0.94 s
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

TEST(ModelMismatch, ObserverDoesNotDegradeTheNominalScenario) {
  // With an exact model the prediction error is not zero: each new plan assumes its own muscle
  // state at the start, and clamped excitations are not executed. The observer reacts to that
  // too; it must not make the nominal run worse (measured: within 2 deg at 0.77 s instead of
  // 0.73 s; final error 9e-5 vs 1.6e-4 deg).
  const auto nominal = flatsos::test::load_arm();
  const auto with = run(nominal, kGainPerSecond);
  const auto without = run(nominal, 0.0);
  std::cout << "exact model: final error " << with.final_error_deg << " deg with the observer (settled within 2 deg: "
            << with.run.settling_time_s << " s), " << without.final_error_deg << " deg without ("
            << without.run.settling_time_s << " s)\n";
  EXPECT_LT(with.final_error_deg, without.final_error_deg + 1e-4);
  ASSERT_GE(with.run.settling_time_s, 0.0);
  EXPECT_LE(with.run.settling_time_s, without.run.settling_time_s + 0.05);
}

TEST(ModelMismatch, ObserverRejectsATorquePulseFasterAndCloserThanThePapersController) {
  // The paper's controller re-plans from the measured state, so it recovers from a pulse too;
  // the observer must do better than that same run without it (measured: 2.2e-4 deg and
  // settled within 2 deg at 0.94 s with it; 1.4e-3 deg and 1.38 s without).
  const auto plant = std::make_shared<const fp::MusculoskeletalModel>(
      fp::load_model_file(flatsos::test::arm_model_path()),
      std::vector<fp::ExternalJointTorque>{{0, std::make_shared<TorquePulse>(0.5, 0.1, -5.0)},  // against the shoulder
                                           {1, std::make_shared<TorquePulse>(0.5, 0.1, 3.0)}});
  const auto with = run(plant, kGainPerSecond);
  const auto without = run(plant, 0.0);
  std::cout << "torque pulse: final error " << with.final_error_deg << " deg with the observer (settled " << with.run.settling_time_s
            << " s), " << without.final_error_deg << " deg without (settled " << without.run.settling_time_s << " s)\n";
  ASSERT_GE(with.run.settling_time_s, 0.0);
  ASSERT_GE(without.run.settling_time_s, 0.0);
  EXPECT_LT(with.run.settling_time_s, without.run.settling_time_s - 0.2);
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
