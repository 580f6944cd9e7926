// Joint limit torques: the law's properties (zero inside the range, pushing back beyond it, the
// full spring past the transition, a damper that only dissipates), its derivatives and potential
// against finite differences and continuity at the transition's ends; in Simbody, the force
// element against what the inverse dynamics subtracts, energy conserved with the undamped spring;
// and the elbow that spun to 831 deg under constant excitation without limits now staying within
// its range plus the transition for 5 s (and leaving it when the limit is switched off).
#include <gtest/gtest.h>

#include "finite_difference.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "flatsos/plugin/integration/forward_simulation.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/model/dual_number.hpp"
#include "flatsos/plugin/model/joint_limit.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"
#include "flatsos/plugin/model/static_equilibrium.hpp"

namespace fp = flatsos::plugin;
using flatsos::test::central_difference;

namespace {

constexpr double kLower = -0.3, kUpper = 1.2;
const fp::JointLimitTorque kLimit{400.0, 0.2, 3.0};

double torque(double q, double qd) { return fp::joint_limit_torque(kLimit, kLower, kUpper, q, qd); }

// d tau / dq and d2 tau / dq2 at (q, qd) by dual numbers.
struct Slopes {
  double first, second;
};
Slopes slopes(double q, double qd) {
  using H = fp::Dual<fp::Dual<double>>;
  const H t = fp::joint_limit_torque(kLimit, kLower, kUpper, H(fp::Dual<double>(q, 1.0), fp::Dual<double>(1.0, 0.0)),
                                     H(qd));
  return {t.derivative.value, t.derivative.derivative};
}

std::string elbow_file() { return std::string(FLATSOS_SOURCE_DIR) + "/models/elbow_posture_dependent.json"; }

// The elbow at q with every tendon at its static equilibrium for activation a.
SimTK::State elbow_at(const fp::MusculoskeletalModel& model, double q_rad, double a) {
  SimTK::State s = model.defaultState();
  model.setJointAngles(s, Eigen::VectorXd::Constant(1, q_rad));
  fp::equilibrate_tendons(model, s, Eigen::VectorXd::Constant(model.numMuscles(), a));
  return s;
}

// The joint angle's extremes over a run, from reports every 2 ms.
struct Extremes {
  double min_rad = 1e300, max_rad = -1e300;
};
Extremes extremes(const fp::SimulationResult& r) {
  Extremes e;
  for (const auto& row : r.states.rows) {
    e.min_rad = std::min(e.min_rad, row[1]);
    e.max_rad = std::max(e.max_rad, row[1]);
  }
  return e;
}

fp::SimulationResult run_with_excitations(const fp::MusculoskeletalModel& model, const Eigen::VectorXd& excitations,
                                          double q0_rad, double duration_s) {
  SimTK::State s = elbow_at(model, q0_rad, 1e-4);
  model.setExcitations(s, excitations);
  fp::SimulationOptions o;
  o.duration_s = duration_s;
  o.integrator = fp::IntegratorKind::MuscleRosenbrock;  // stiff: muscles at full activation and the stop
  o.accuracy = 1e-6;
  o.report_interval_s = 0.002;
  return fp::simulate(model, s, o);
}

}  // namespace

TEST(JointLimitTorque, ZeroInsideTheRangeAndPushingBackBeyondIt) {
  for (double q = kLower; q <= kUpper; q += 0.01)
    for (double qd : {-5.0, 0.0, 5.0}) EXPECT_EQ(torque(q, qd), 0.0) << q;
  EXPECT_EQ(torque(kUpper, 3.0), 0.0);
  EXPECT_EQ(torque(kLower, -3.0), 0.0);
  for (double x : {1e-3, 0.05, 0.1, 0.19, 0.2, 0.5}) {
    EXPECT_LT(torque(kUpper + x, 0.0), 0.0) << x;
    EXPECT_GT(torque(kLower - x, 0.0), 0.0) << x;
    // At rest the two ends are mirror images.
    EXPECT_NEAR(torque(kUpper + x, 0.0), -torque(kLower - x, 0.0), 1e-12 * kLimit.stiffness_N_m_per_rad) << x;
    // More penetration, more torque.
    EXPECT_LT(torque(kUpper + x + 1e-3, 0.0), torque(kUpper + x, 0.0)) << x;
  }
  // Past the transition: the whole spring and the whole damper.
  EXPECT_NEAR(torque(kUpper + 0.3, 2.0), -(400.0 * 0.3 + 3.0 * 2.0), 1e-12);
  EXPECT_NEAR(torque(kLower - 0.3, -2.0), 400.0 * 0.3 + 3.0 * 2.0, 1e-12);
  // Halfway through the transition the step is exactly 1/2.
  EXPECT_NEAR(torque(kUpper + 0.1, 0.0), -0.5 * 400.0 * 0.1, 1e-12);
  // A disabled limit is no torque anywhere.
  EXPECT_EQ(fp::joint_limit_torque(fp::JointLimitTorque{}, kLower, kUpper, 5.0, 1.0), 0.0);
}

TEST(JointLimitTorque, TheDamperOnlyDissipates) {
  for (double x : {0.01, 0.1, 0.3})
    for (double qd : {-4.0, -0.5, 0.5, 4.0}) {
      // The damper's share is the torque minus its value at rest; its power is never positive.
      EXPECT_LE((torque(kUpper + x, qd) - torque(kUpper + x, 0.0)) * qd, 0.0) << x << " " << qd;
      EXPECT_LE((torque(kLower - x, qd) - torque(kLower - x, 0.0)) * qd, 0.0) << x << " " << qd;
    }
}

TEST(JointLimitTorque, DerivativesMatchFiniteDifferencesAndAreContinuousAtTheTransitionsEnds) {
  for (double q : {kLower - 0.35, kLower - 0.15, kLower - 0.02, kUpper + 0.03, kUpper + 0.12, kUpper + 0.4}) {
    for (double qd : {-2.0, 0.7}) {
      const Slopes s = slopes(q, qd);
      EXPECT_MATCHES_FINITE_DIFFERENCE(s.first, central_difference([&](double x) { return torque(x, qd); }, q, 1e-5))
          << q;
      EXPECT_MATCHES_FINITE_DIFFERENCE(
          s.second, central_difference([&](double x) { return slopes(x, qd).first; }, q, 1e-5))
          << q;
    }
  }
  // Torque, slope and curvature agree from both sides of each end of the transitions (C2); the
  // damper's share included (qd != 0).
  for (double edge : {kUpper, kUpper + 0.2, kLower, kLower - 0.2}) {
    const double d = 1e-9, qd = 1.5;
    EXPECT_NEAR(torque(edge - d, qd), torque(edge + d, qd), 1e-5) << edge;
    EXPECT_NEAR(slopes(edge - d, qd).first, slopes(edge + d, qd).first, 1e-4) << edge;
    EXPECT_NEAR(slopes(edge - d, qd).second, slopes(edge + d, qd).second, 1e-2) << edge;
  }
  // ...while the curvature is far from zero inside the transition: the checks above are not trivial.
  EXPECT_GT(std::abs(slopes(kUpper + 0.05, 0.0).second), 1e3);
}

TEST(JointLimitTorque, TheSpringIsMinusThePotentialsSlope) {
  auto potential = [](double q) { return fp::joint_limit_potential_energy(kLimit, kLower, kUpper, q); };
  EXPECT_EQ(potential(0.5 * (kLower + kUpper)), 0.0);
  for (double q : {kLower - 0.4, kLower - 0.1, kLower - 0.01, kUpper + 0.02, kUpper + 0.15, kUpper + 0.35})
    EXPECT_MATCHES_FINITE_DIFFERENCE(-torque(q, 0.0), central_difference(potential, q, 1e-5)) << q;
  // Continuous at the transition's end, where its two formulas meet.
  EXPECT_NEAR(potential(kUpper + 0.2 - 1e-12), potential(kUpper + 0.2 + 1e-12), 1e-9);
}

TEST(JointLimits, SimbodyAppliesWhatTheInverseDynamicsSubtracts) {
  const auto model = fp::MusculoskeletalModel::fromFile(elbow_file());
  ASSERT_TRUE(model->hasJointLimits());
  const double upper = model->description().joints[0].range_rad[1];
  for (double q : {0.5, upper + 0.05, upper + 0.3, -0.1})
    for (double qd : {-2.0, 1.0}) {
      SimTK::State s = elbow_at(*model, q, 0.2);
      model->setJointSpeeds(s, Eigen::VectorXd::Constant(1, qd));
      model->system().realize(s, SimTK::Stage::Acceleration);
      const Eigen::VectorXd qv = Eigen::VectorXd::Constant(1, q), qdv = Eigen::VectorXd::Constant(1, qd);
      const Eigen::VectorXd qdd = Eigen::VectorXd::Constant(1, s.getUDot()[0]);
      // M qdd + C qd + g - tau_limit = R(q) F: the muscles' torque that Simbody applied.
      const Eigen::VectorXd needed = model->inverseDynamics(qv, qdv, qdd);
      const Eigen::VectorXd applied = model->muscleTorques(qv, model->tendonForces(s));
      EXPECT_NEAR(needed[0], applied[0], 1e-9 * (1.0 + std::abs(applied[0]))) << q << " " << qd;
      // Beyond the range the limit is a large part of the balance.
      Eigen::VectorXd limit(1);
      model->pinTree().jointLimitTorques(qv, qdv, limit);
      if (q > upper || q < 0.0) EXPECT_GT(std::abs(limit[0]), 1.0) << q;
      else EXPECT_EQ(limit[0], 0.0);
    }
}

TEST(JointLimits, TheUndampedSpringConservesEnergyInASwingThroughTheLimit) {
  // Muscles too weak to do work (1 uN), no damper: the forearm swings into the stop and back, and
  // kinetic + gravitational + the spring's potential energy stays constant.
  fp::ModelDescription d = fp::load_model_file(elbow_file());
  d.joints[0].limit.damping_N_m_s_per_rad = 0.0;
  for (auto& m : d.muscles) m.parameters.max_isometric_force_N = 1e-6;
  const fp::MusculoskeletalModel model(d);
  SimTK::State s = elbow_at(model, 2.3, 1e-4);
  model.setJointSpeeds(s, Eigen::VectorXd::Constant(1, 4.0));
  fp::SimulationOptions o;
  o.duration_s = 0.6;
  o.accuracy = 1e-10;
  o.report_interval_s = 0.002;
  const double energy0 = model.mechanicalEnergy(s);
  const fp::SimulationResult r = fp::simulate(model, s, o);
  ASSERT_TRUE(r.finite) << r.message;
  const Extremes e = extremes(r);
  EXPECT_GT(e.max_rad, 2.5 + 0.1);  // well into the transition: the spring stored energy
  EXPECT_NEAR(model.mechanicalEnergy(r.final_state), energy0, 1e-6 * std::abs(energy0));
  double worst = 0.0;
  for (const auto& row : r.states.rows) {
    SimTK::State at = r.final_state;
    model.setJointAngles(at, Eigen::VectorXd::Constant(1, row[1]));
    model.setJointSpeeds(at, Eigen::VectorXd::Constant(1, row[2]));
    worst = std::max(worst, std::abs(model.mechanicalEnergy(at) - energy0));
  }
  EXPECT_LT(worst, 1e-5 * std::abs(energy0));
}

TEST(JointLimits, AnElbowUnderConstantFullExcitationStaysWithinItsRangeAndTransitionForFiveSeconds) {
  const auto model = fp::MusculoskeletalModel::fromFile(elbow_file());
  const fp::JointDescription& joint = model->description().joints[0];
  const double lower = joint.range_rad[0], upper = joint.range_rad[1], transition = joint.limit.transition_rad;
  // Every muscle at full excitation: the flexors win and drive the elbow into its upper stop.
  const fp::SimulationResult all = run_with_excitations(*model, Eigen::VectorXd::Ones(3), 1.0, 5.0);
  ASSERT_TRUE(all.finite) << all.message;
  const Extremes flexed = extremes(all);
  EXPECT_GT(flexed.max_rad, upper);  // it does reach the stop
  EXPECT_LE(flexed.max_rad, upper + transition);
  EXPECT_GE(flexed.min_rad, lower - transition);
  // The triceps alone drives it into the lower stop.
  const fp::SimulationResult triceps = run_with_excitations(*model, Eigen::Vector3d(0.0, 0.0, 1.0), 1.0, 5.0);
  ASSERT_TRUE(triceps.finite) << triceps.message;
  const Extremes extended = extremes(triceps);
  EXPECT_LT(extended.min_rad, lower);
  EXPECT_GE(extended.min_rad, lower - transition);
  EXPECT_LE(extended.max_rad, upper + transition);

  // The same elbow without its limit leaves the range: what the limit is for.
  fp::ModelDescription d = model->description();
  d.joints[0].limit = fp::JointLimitTorque{};
  const fp::MusculoskeletalModel free_elbow(d);
  const fp::SimulationResult spun = run_with_excitations(free_elbow, Eigen::VectorXd::Ones(3), 1.0, 1.0);
  EXPECT_TRUE(!spun.finite || extremes(spun).max_rad > upper + transition);
}
