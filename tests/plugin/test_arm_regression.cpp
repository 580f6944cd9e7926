// The Simbody arm built from models/arm_richter_warner.json reproduces the regression facts of
// the paper's arm data, computed independently from the parameter table.
#include <gtest/gtest.h>

#include "arm_fixture.hpp"
#include "flatsos/plugin/model/static_equilibrium.hpp"

using flatsos::test::deg;

TEST(ArmRegression, MassMatrixAtStraightElbow) {
  const auto arm = flatsos::test::load_arm();
  const Eigen::MatrixXd m = arm->massMatrix(Eigen::Vector2d(0.3, 0.0));
  // DESIGN 2.4 gives 5 significant digits.
  EXPECT_NEAR(m(0, 0), 0.64011, 5e-6);
  EXPECT_NEAR(m(0, 1), 0.25003, 5e-6);
  EXPECT_NEAR(m(1, 0), 0.25003, 5e-6);
  EXPECT_NEAR(m(1, 1), 0.12330, 5e-6);
}

TEST(ArmRegression, GravityTorque) {
  const auto arm = flatsos::test::load_arm();
  const Eigen::Vector2d zero = Eigen::Vector2d::Zero();
  const Eigen::VectorXd tau = arm->inverseDynamics(Eigen::Vector2d(0.0, deg(10)), zero, zero);
  EXPECT_NEAR(tau[0], 12.570, 5e-4);
  EXPECT_NEAR(tau[1], 3.710, 5e-4);
}

TEST(ArmRegression, StaticEquilibriumOfThePaperActivations) {
  const auto arm = flatsos::test::load_arm();
  SimTK::State s = arm->defaultState();
  arm->setJointAngles(s, Eigen::Vector2d(0.0, deg(10)));
  flatsos::plugin::equilibrate_tendons(*arm, s, flatsos::test::paper_a0());
  const Eigen::VectorXd ls = arm->tendonLengths(s);
  const Eigen::VectorXd f = arm->tendonForces(s);
  const double ls_expected[] = {0.0546, 0.0540, 0.2347, 0.1919, 0.1941, 0.0176};
  const double f_expected[] = {108.0, 10.2, 288.9, 32.5, 159.7, 27.7};
  for (int j = 0; j < 6; ++j) {
    EXPECT_NEAR(ls[j], ls_expected[j], 0.5e-4) << j;
    EXPECT_NEAR(f[j], f_expected[j], 0.05) << j;
  }
  const Eigen::VectorXd tau = arm->muscleTorques(f);
  EXPECT_NEAR(tau[0], 12.576, 5e-4);
  EXPECT_NEAR(tau[1], 3.727, 5e-4);
  // The same torques come out of the Simbody force elements: at rest, the acceleration equals
  // M^-1 (tau_muscle - g), with g from inverse dynamics.
  arm->system().realize(s, SimTK::Stage::Acceleration);
  const Eigen::Vector2d qdd(s.getUDot()[0], s.getUDot()[1]);
  const Eigen::VectorXd residual = arm->inverseDynamics(arm->jointAngles(s), arm->jointSpeeds(s), qdd);
  EXPECT_NEAR(residual[0], tau[0], 1e-10);
  EXPECT_NEAR(residual[1], tau[1], 1e-10);
}

TEST(ArmRegression, EquilibriumIsARestPointOfTheMuscleStates) {
  const auto arm = flatsos::test::load_arm();
  SimTK::State s = arm->defaultState();
  arm->setJointAngles(s, Eigen::Vector2d(0.0, deg(10)));
  flatsos::plugin::equilibrate_tendons(*arm, s, flatsos::test::paper_a0());
  arm->setExcitations(s, flatsos::test::paper_a0());
  arm->system().realize(s, SimTK::Stage::Acceleration);
  for (int j = 0; j < arm->numMuscles(); ++j) {
    // Fiber isometric at u = 0 to round-off of the tendon length (1e-17 m scale) times the slope.
    EXPECT_NEAR(arm->muscle(j).getTendonLengthDerivative(s), 0.0, 1e-11) << j;
    EXPECT_NEAR(arm->muscle(j).getActivationDerivative(s), 0.0, 1e-15) << j;
  }
}
