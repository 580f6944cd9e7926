// The muscle state estimator (muscle_state_estimator.hpp): the model's muscles under given
// excitations along a measured joint motion, against Simbody's simulation of the same arm, and
// its integration order where the joint motion is exact.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "../plugin/arm_fixture.hpp"
#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/planner/muscle_state_estimator.hpp"
#include "flatsos/plugin/integration/stepper.hpp"
#include "flatsos/plugin/model/model_workspace.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
using flatsos::test::deg;

namespace {

// Excitation ramps over [t0, t0 + period]: muscle j from the paper's a0 to a value well apart,
// so activations and tendons move within the period.
fp::ExcitationPolynomial ramp(int j, double t0, double period_s) {
  fp::ExcitationPolynomial piece;
  const double start = flatsos::test::paper_a0()[j];
  piece.count = 2;
  piece.coefficients[0] = start;
  piece.coefficients[1] = (j % 2 == 0 ? 0.9 : 0.02) - start;
  piece.start_time_s = t0;
  piece.duration_s = period_s;
  return piece;
}

double worst_relative_force_error(const fp::MusculoskeletalModel& arm, const Eigen::VectorXd& tendon_m,
                                  const Eigen::VectorXd& reference_m) {
  double worst = 0.0;
  for (int j = 0; j < arm.numMuscles(); ++j) {
    const auto& p = arm.muscle(j).getParameters();
    const double f = flatsos::muscles::tendon_force(p, tendon_m[j]), ref = flatsos::muscles::tendon_force(p, reference_m[j]);
    worst = std::max(worst, std::abs(f - ref) / p.max_isometric_force_N);
  }
  return worst;
}
}  // namespace

TEST(MuscleStateEstimator, ItsMusclesGiveTheTorqueOfTheMotionSimbodySimulates) {
  // The arm moves freely for one control period under the ramps; the estimator sees only q, qd at
  // both ends and the excitations. With the plant equal to the model, the torque the measured
  // motion needs (inverse dynamics of q, qd, qdd) is the muscles' torque: the estimator's
  // muscles must give it, which is what keeps the disturbance observer at 0 on an exact model.
  const auto arm = flatsos::test::load_arm();
  SimTK::State s = flatsos::test::paper_state(*arm);
  constexpr double kPeriod = 0.05;
  for (int j = 0; j < 6; ++j) arm->muscle(j).setExcitationPolynomial(s, ramp(j, 0.0, kPeriod));
  fpl::MuscleStateEstimator estimator(arm);
  estimator.start(arm->tendonLengths(s), arm->activations(s), 0.0);
  for (int j = 0; j < 6; ++j) estimator.setExcitation(j, ramp(j, 0.0, kPeriod));
  arm->system().realize(s, SimTK::Stage::Acceleration);
  const Eigen::VectorXd q0 = arm->jointAngles(s), qd0 = arm->jointSpeeds(s);
  Eigen::VectorXd qdd0(2);
  for (int i = 0; i < 2; ++i) qdd0[i] = arm->joint(i).getOneUDot(s, 0);

  auto stepper = fp::make_stepper(*arm, fp::IntegratorKind::RungeKuttaMerson, 1e-11);
  stepper->initialize(s);
  ASSERT_TRUE(stepper->advanceTo(kPeriod));
  SimTK::State end = stepper->state();
  arm->system().realize(end, SimTK::Stage::Acceleration);
  const Eigen::VectorXd q1 = arm->jointAngles(end), qd1 = arm->jointSpeeds(end);
  Eigen::VectorXd qdd1(2);
  for (int i = 0; i < 2; ++i) qdd1[i] = arm->joint(i).getOneUDot(end, 0);
  ASSERT_GT((q1 - q0).cwiseAbs().maxCoeff(), deg(0.5)) << "the test needs a moving arm";
  ASSERT_GT((arm->activations(end) - arm->activations(s)).cwiseAbs().maxCoeff(), 0.2) << "and moving activations";

  ASSERT_TRUE(estimator.advance({q0, qd0, qdd0}, {q1, qd1, qdd1}, kPeriod));
  EXPECT_DOUBLE_EQ(estimator.time_s(), kPeriod);
  fp::ModelWorkspace ws = arm->makeWorkspace();
  Eigen::VectorXd needed(2), estimated;
  arm->inverseDynamics(ws, q1, qd1, qdd1, needed);
  estimator.muscleTorques(q1, estimated);
  const double activation_error = (estimator.activations() - arm->activations(end)).cwiseAbs().maxCoeff();
  const double force_error = worst_relative_force_error(*arm, estimator.tendonLengths_m(), arm->tendonLengths(end));
  const double torque_error = (needed - estimated).cwiseAbs().maxCoeff();
  std::cout << "one period: activation error " << activation_error << ", tendon force error " << force_error
            << " Fmax, torque error " << torque_error << " N m of " << needed.cwiseAbs().maxCoeff() << " N m\n";
  // Measured: 8.6e-6, 1.6e-4 Fmax, 0.0085 N m (2.4e-4 of the torque). The floor is the quintic
  // through the ends' q, qd, qdd: with the ramps' sharp rise the motion is not quite a quintic
  // (the same errors at an accuracy of 1e-10).
  EXPECT_LT(activation_error, 1e-4);
  EXPECT_LT(force_error, 5e-4);
  EXPECT_LT(torque_error, 0.02);
}

TEST(MuscleStateEstimator, ItsErrorFollowsTheAccuracyAskedFor) {
  // Joints held (their motion is then exact), the muscles' ramps from the paper's state: against
  // a run at 1e-10, the error at each accuracy stays within a small multiple of it, and shrinks
  // with it (a step-size control that did nothing would give one error for all).
  const auto arm = flatsos::test::load_arm();
  const SimTK::State s = flatsos::test::paper_state(*arm);
  const Eigen::VectorXd q = arm->jointAngles(s), rest = Eigen::VectorXd::Zero(2);
  const auto run = [&](double accuracy) {
    fpl::MuscleStateEstimator e(arm, accuracy);
    e.start(arm->tendonLengths(s), arm->activations(s), 0.0);
    for (int j = 0; j < 6; ++j) e.setExcitation(j, ramp(j, 0.0, 0.05));
    EXPECT_TRUE(e.advance({q, rest, rest}, {q, rest, rest}, 0.05));
    return e.tendonLengths_m();
  };
  const Eigen::VectorXd reference = run(1e-10);
  double previous = 1.0;
  for (double accuracy : {1e-3, 1e-5, 1e-7}) {
    const double error = worst_relative_force_error(*arm, run(accuracy), reference);
    std::cout << "held joints, accuracy " << accuracy << ": tendon force error " << error << " Fmax\n";
    EXPECT_LT(error, 20 * accuracy);
    EXPECT_LT(error, previous / 10);
    previous = error;
  }
}

TEST(MuscleStateEstimator, RefusesWhatItCannotUse) {
  const auto arm = flatsos::test::load_arm();
  EXPECT_THROW(fpl::MuscleStateEstimator(nullptr), std::invalid_argument);
  EXPECT_THROW(fpl::MuscleStateEstimator(arm, 0.0), std::invalid_argument);
  EXPECT_THROW(fpl::MuscleStateEstimator(arm, NAN), std::invalid_argument);
  fpl::MuscleStateEstimator e(arm);
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(2);
  EXPECT_THROW(e.advance({q, q, q}, {q, q, q}, 0.1), std::logic_error);
  EXPECT_THROW(e.start(Eigen::VectorXd::Zero(5), Eigen::VectorXd::Zero(6), 0.0), std::invalid_argument);
  EXPECT_THROW(e.start(Eigen::VectorXd::Constant(6, NAN), Eigen::VectorXd::Zero(6), 0.0), std::invalid_argument);
  e.start(arm->tendonLengths(flatsos::test::paper_state(*arm)), flatsos::test::paper_a0(), 1.0);
  EXPECT_THROW(e.advance({q, q, q}, {q, q, q}, 0.5), std::invalid_argument);  // back in time
  const Eigen::VectorXd before = e.tendonLengths_m(), bad = Eigen::VectorXd::Constant(2, NAN);
  EXPECT_FALSE(e.advance({q, q, q}, {bad, q, q}, 1.05));
  EXPECT_EQ(e.tendonLengths_m(), before);
}
