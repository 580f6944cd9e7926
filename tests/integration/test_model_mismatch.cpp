// Model mismatch and disturbances: the RH controller plans on the nominal arm while the
// simulated arm differs (each muscle's Fmax +-20 %, segment masses +-10 %, moment arms +-10 %)
// or is pushed by a torque pulse mid-motion. The disturbance observer integrates the plan's
// prediction error (joint torque the plant did not deliver), which makes the loop offset free.
// Measured (3 s runs, printed by the test), gain 1: every corner ends within 0.001 deg of the
// target and settles within 2 deg by 0.65-0.94 s; without the observer the corners end 3.5-32 deg
// off. Gains 0.5 to 2 all end within 0.07 deg. A torque pulse is rejected to < 0.001 deg.
#include <gtest/gtest.h>

#include <iostream>

#include "../planner/scenario_fixture.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/planner/receding_horizon.hpp"

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

struct Outcome {
  double final_error_deg = 0.0;
  double settling_s = -1.0;
  int failures = 0;
};

Outcome run(const fp::MusculoskeletalModel& plant, double observer_gain) {
  const auto nominal = flatsos::test::load_arm();
  const fpl::FlatOutputMap flat(*nominal);
  fpl::RecedingHorizonControllerOptions o;
  o.plan.target_q_rad = Eigen::Vector2d(deg(80), deg(80));
  o.plan.reserves_N = Eigen::VectorXd::Constant(6, 1.0);
  o.plan.solver = fpl::SlpSolver::VertexEnumeration;
  o.disturbance_observer_gain = observer_gain;
  // The plant starts at rest in its own minimum-effort equilibrium.
  SimTK::State s = plant.defaultState();
  const fpl::FlatOutputMap plant_flat(plant);
  fpl::set_minimum_effort_rest_state(plant_flat, s, Eigen::Vector2d(deg(20), deg(20)), o.plan.reserves_N);
  fpl::RecedingHorizonController controller(flat, o);
  const auto r = fpl::simulate_closed_loop(controller, plant, s, 3.0, 1e-8, 5, deg(2), fp::IntegratorKind::CPodesBdf);
  Outcome out;
  EXPECT_TRUE(r.finite);
  const Eigen::VectorXd q = plant.jointAngles(r.final_state);
  out.final_error_deg = std::max(std::abs(q[0] - deg(80)), std::abs(q[1] - deg(80))) / deg(1);
  out.settling_s = r.settling_time_s;
  out.failures = controller.planFailures();
  return out;
}

}  // namespace

TEST(ModelMismatch, SettlesWithinTwoDegreesInEveryCornerWithTheObserver) {
  double worst_with = 0.0, worst_without = 0.0;
  std::string worst_case;
  for (double fmax : {0.8, 1.2})
    for (double mass : {0.9, 1.1})
      for (double arm : {0.9, 1.1}) {
        const fp::MusculoskeletalModel plant(mismatched({fmax, mass, arm}));
        const Outcome with = run(plant, 1.0);
        const Outcome without = run(plant, 0.0);
        std::cout << "Fmax x" << fmax << " mass x" << mass << " moment arms x" << arm << ": final error "
                  << with.final_error_deg << " deg with the observer (settled within 2 deg: " << with.settling_s
                  << " s), " << without.final_error_deg << " deg without\n";
        EXPECT_EQ(with.failures, 0);
        EXPECT_EQ(without.failures, 0);
        EXPECT_LT(with.final_error_deg, 2.0);
        EXPECT_GE(with.settling_s, 0.0) << "never settled within 2 deg";
        if (with.final_error_deg >= worst_with) {
          worst_with = with.final_error_deg;
          worst_case = "Fmax x" + std::to_string(fmax) + ", mass x" + std::to_string(mass) + ", arms x" + std::to_string(arm);
        }
        worst_without = std::max(worst_without, without.final_error_deg);
      }
  std::cout << "worst case with the observer: " << worst_case << ": " << worst_with << " deg (without: " << worst_without << " deg)\n";
  // The mismatch is real: the paper's controller alone misses the 2 deg.
  EXPECT_GT(worst_without, 2.0);
}

TEST(ModelMismatch, ObserverDoesNotDegradeTheNominalScenario) {
  // With an exact model the prediction error is not zero: each new plan assumes its own muscle
  // state at the start, and clamped excitations are not executed. The observer reacts to that
  // too; it must not make the nominal run worse (measured: within 2 deg at 0.77 s instead of
  // 0.73 s, within 1 deg at 0.83 s instead of 1.11 s; final error 9e-5 vs 1.6e-4 deg).
  const auto nominal = flatsos::test::load_arm();
  const Outcome with = run(*nominal, 1.0);
  const Outcome without = run(*nominal, 0.0);
  std::cout << "exact model: final error " << with.final_error_deg << " deg with the observer (settled within 2 deg: "
            << with.settling_s << " s), " << without.final_error_deg << " deg without (" << without.settling_s << " s)\n";
  EXPECT_EQ(with.failures, 0);
  EXPECT_LT(with.final_error_deg, without.final_error_deg + 1e-3);
  EXPECT_GE(with.settling_s, 0.0);
  EXPECT_LE(with.settling_s, without.settling_s + 0.05);
}

TEST(ModelMismatch, ObserverRejectsATorquePulse) {
  fp::MusculoskeletalModel plant(fp::load_model_file(flatsos::test::arm_model_path()));
  plant.addJointTorque(0, std::make_shared<TorquePulse>(0.5, 0.1, -5.0));  // 5 N m against the shoulder
  plant.addJointTorque(1, std::make_shared<TorquePulse>(0.5, 0.1, 3.0));
  const Outcome with = run(plant, 1.0);
  const Outcome without = run(plant, 0.0);
  std::cout << "torque pulse: final error " << with.final_error_deg << " deg with the observer (settled " << with.settling_s
            << " s), " << without.final_error_deg << " deg without\n";
  EXPECT_EQ(with.failures, 0);
  EXPECT_GE(with.settling_s, 0.0);
  EXPECT_LT(with.final_error_deg, 2.0);
}
