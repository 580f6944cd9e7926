// The muscle Rosenbrock-W integrator (ROS34PW2, implicit in each muscle's states): its order of
// convergence, agreement with Simbody's own integrators on a stiff run, error control, and the
// limits it states (constraints, quaternions) with clear errors.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <string>

#include "arm_fixture.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"
#include "flatsos/plugin/integration/muscle_rosenbrock_integrator.hpp"
#include "flatsos/plugin/model/static_equilibrium.hpp"

namespace fp = flatsos::plugin;
using flatsos::test::deg;

namespace {

// Smooth excitations that keep some muscles near a ~ 0.005, where the tendon ODE is stiff.
class SmoothPulse : public fp::ExcitationSignal {
 public:
  SmoothPulse(double base, double peak, double frequency_hz, double phase)
      : base_(base), peak_(peak), f_(frequency_hz), phase_(phase) {}
  double value(double t) const override {
    const double s = std::sin(2.0 * flatsos::test::kPi * (f_ * t + phase_));
    return base_ + peak_ * s * s;
  }

 private:
  double base_, peak_, f_, phase_;
};

SimTK::State stiff_start(const fp::MusculoskeletalModel& arm) {
  const double base_activation = 0.005;  // d(dL_S/dt)/dL_S down to ~ -1e4 1/s: stiff
  SimTK::State s = arm.defaultState();
  arm.setJointAngles(s, Eigen::Vector2d(deg(20), deg(60)));
  const Eigen::VectorXd a0 = Eigen::VectorXd::Constant(6, base_activation);
  fp::equilibrate_tendons(arm, s, a0);
  arm.setActivations(s, a0);
  for (int j = 0; j < arm.numMuscles(); ++j)
    arm.muscle(j).setExcitationSignal(s, std::make_shared<SmoothPulse>(base_activation, 0.25, 1.3, j / 6.0));
  return s;
}


Eigen::VectorXd final_y(const fp::MusculoskeletalModel& arm, const SimTK::State& s0, fp::Stepper& stepper,
                        double t_end) {
  stepper.initialize(s0);
  EXPECT_TRUE(stepper.advanceTo(t_end));
  EXPECT_DOUBLE_EQ(stepper.state().getTime(), t_end);
  (void)arm;
  const SimTK::Vector& y = stepper.state().getY();
  Eigen::VectorXd out(y.size());
  for (int i = 0; i < y.size(); ++i) out[i] = y[i];
  return out;
}

std::unique_ptr<fp::MuscleRosenbrockIntegrator> rosenbrock(const fp::MusculoskeletalModel& arm, double accuracy) {
  std::vector<fp::HillMuscle> muscles;
  for (int j = 0; j < arm.numMuscles(); ++j) muscles.push_back(arm.muscle(j));
  return std::make_unique<fp::MuscleRosenbrockIntegrator>(arm.system(), muscles, accuracy);
}

// initialize() throws std::invalid_argument whose message names `what`.
void expect_refused_at_initialize(fp::MuscleRosenbrockIntegrator& integ, const SimTK::State& s, const std::string& what) {
  try {
    integ.initialize(s);
    ADD_FAILURE() << "accepted a system with " << what;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(MuscleRosenbrock, ThirdOrderWithFixedSteps) {
  // The coefficients and the W-method property: with no muscles the approximate Jacobian is
  // zero and the method must still be third order. A smooth double pendulum; observed order from
  // successive differences, log2(|y_h - y_h/2| / |y_h/2 - y_h/4|). (With muscles the laws are
  // only C1 -- force-velocity at u = 0, tendon at slack -- which caps any method's observed
  // order near 2; the adaptive tests below check accuracy against a reference there.)
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter(system);
  SimTK::GeneralForceSubsystem forces(system);
  SimTK::Force::UniformGravity gravity(forces, matter, SimTK::Vec3(0, -9.81, 0));
  const SimTK::Body::Rigid link(SimTK::MassProperties(1.0, SimTK::Vec3(0.2, 0, 0), SimTK::Inertia(0.01).shiftFromMassCenter(SimTK::Vec3(0.2, 0, 0), 1.0)));
  SimTK::MobilizedBody::Pin upper(matter.Ground(), SimTK::Transform(), link, SimTK::Transform());
  SimTK::MobilizedBody::Pin lower(upper, SimTK::Transform(SimTK::Vec3(0.3, 0, 0)), link, SimTK::Transform());
  system.realizeTopology();
  SimTK::State s0 = system.getDefaultState();
  upper.setOneQ(s0, 0, 0.4);
  lower.setOneQ(s0, 0, 1.1);
  const double t_end = 0.2;
  std::vector<Eigen::Vector2d> finals;
  for (double h : {4e-3, 2e-3, 1e-3, 5e-4}) {
    fp::MuscleRosenbrockIntegrator integ(system, {}, 1e-6);
    integ.setFixedStepSize(h);
    integ.initialize(s0);
    ASSERT_TRUE(integ.advanceTo(t_end));
    EXPECT_EQ(integ.stepsTaken(), std::lround(t_end / h));
    finals.emplace_back(upper.getOneQ(integ.state(), 0), lower.getOneQ(integ.state(), 0));
  }
  for (std::size_t i = 2; i < finals.size(); ++i) {
    const double coarse = (finals[i - 2] - finals[i - 1]).cwiseAbs().maxCoeff();
    const double fine = (finals[i - 1] - finals[i]).cwiseAbs().maxCoeff();
    const double order = std::log2(coarse / fine);
    EXPECT_GT(order, 2.8) << coarse << " -> " << fine;
    EXPECT_LT(order, 3.3) << coarse << " -> " << fine;
  }
}

TEST(MuscleRosenbrock, AgreesWithRungeKuttaMersonOnAStiffRunWithFewerSteps) {
  const auto arm = flatsos::test::load_arm();
  const SimTK::State s0 = stiff_start(*arm);
  const double t_end = 1.0;
  auto reference = fp::make_stepper(*arm, fp::IntegratorKind::RungeKuttaMerson, 1e-11);
  const Eigen::VectorXd ref = final_y(*arm, s0, *reference, t_end);
  double previous_error = 1e9;
  for (double accuracy : {1e-5, 1e-7}) {
    auto integ = rosenbrock(*arm, accuracy);
    const Eigen::VectorXd y = final_y(*arm, s0, *integ, t_end);
    auto rkm = fp::make_stepper(*arm, fp::IntegratorKind::RungeKuttaMerson, accuracy);
    final_y(*arm, s0, *rkm, t_end);
    const double q_error_deg = (y.head(2) - ref.head(2)).cwiseAbs().maxCoeff() * 180.0 / flatsos::test::kPi;
    // Error control: the global error follows the requested accuracy down.
    EXPECT_LT(q_error_deg, accuracy * 1e3) << accuracy;
    EXPECT_LT(q_error_deg, previous_error);
    previous_error = q_error_deg;
    EXPECT_LT(integ->stepsTaken() * (accuracy > 1e-6 ? 5 : 2), rkm->stepsTaken()) << accuracy;
    EXPECT_GE(integ->stepsAttempted(), integ->stepsTaken());
    std::cout << "accuracy " << accuracy << ": Rosenbrock " << integ->stepsTaken() << " steps, error " << q_error_deg
              << " deg; Runge-Kutta-Merson " << rkm->stepsTaken() << " steps\n";
  }
}

TEST(MuscleRosenbrock, DenseOutputAgreesWithSteppingToEachReport) {
  // Reports from the continuous extension (steps not cut) vs the generic path that steps to
  // every report time: the same solution to within the integration error.
  const auto arm = flatsos::test::load_arm();
  const SimTK::State s0 = stiff_start(*arm);
  std::vector<double> times;
  for (int k = 1; k <= 50; ++k) times.push_back(0.01 * k);
  std::vector<Eigen::VectorXd> dense, stepped;
  auto collect = [](std::vector<Eigen::VectorXd>& into) {
    return [&into](const SimTK::State& s) {
      Eigen::VectorXd y(s.getNY());
      for (int i = 0; i < s.getNY(); ++i) y[i] = s.getY()[i];
      into.push_back(y);
    };
  };
  auto a = rosenbrock(*arm, 1e-8), b = rosenbrock(*arm, 1e-8);
  a->initialize(s0);
  b->initialize(s0);
  ASSERT_TRUE(a->advanceTo(0.5, times, collect(dense)));
  const auto record_stepped = collect(stepped);
  for (double t : times) {  // steps cut at every report time
    ASSERT_TRUE(b->advanceTo(t));
    record_stepped(b->state());
  }
  ASSERT_EQ(dense.size(), times.size());
  ASSERT_EQ(stepped.size(), times.size());
  double q_diff = 0.0;
  for (std::size_t k = 0; k < times.size(); ++k) q_diff = std::max(q_diff, (dense[k] - stepped[k]).head(2).cwiseAbs().maxCoeff());
  EXPECT_LT(q_diff, 1e-6);  // rad
  EXPECT_LT(a->stepsTaken(), b->stepsTaken());  // reports no longer cut steps
  // The last report is the end of the run itself.
  EXPECT_EQ(a->state().getTime(), 0.5);
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(dense.back()[i], a->state().getY()[i], 1e-12);
}

TEST(MuscleRosenbrock, KeepsItsStepSizeAcrossInitialize) {
  const auto arm = flatsos::test::load_arm();
  const SimTK::State s0 = stiff_start(*arm);
  auto integ = rosenbrock(*arm, 1e-6);
  integ->initialize(s0);
  ASSERT_TRUE(integ->advanceTo(0.05));
  const double h = integ->nextStepSize();
  EXPECT_GT(h, 1e-4);  // grown from its first trial of 1e-4 s
  integ->initialize(integ->state());
  EXPECT_EQ(integ->nextStepSize(), h);
}

TEST(MuscleRosenbrock, TakesItsDerivativesFromTheDynamicsStageWhereTheyAreSimbodysOwn) {
  // The arm (muscles the only z, no constraints): the tree's accelerations under the Dynamics
  // stage's forces, checked at initialize against realize(Acceleration); the stiff run above
  // then tests them against Runge-Kutta-Merson.
  const auto arm = flatsos::test::load_arm();
  auto integ = rosenbrock(*arm, 1e-6);
  integ->initialize(stiff_start(*arm));
  EXPECT_TRUE(integ->usesDynamicsStageDerivatives());

}

TEST(MuscleRosenbrock, RejectsSystemsItCannotIntegrateAndBadArguments) {
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter(system);
  SimTK::MobilizedBody::Ball ball(matter.Ground(), SimTK::Transform(),
                                  SimTK::Body::Rigid(SimTK::MassProperties(1.0, SimTK::Vec3(0), SimTK::Inertia(1))),
                                  SimTK::Transform(SimTK::Vec3(0, 1, 0)));
  system.realizeTopology();
  fp::MuscleRosenbrockIntegrator integ(system, {}, 1e-6);
  expect_refused_at_initialize(integ, system.getDefaultState(), "quaternions");
  // Prescribed motion: Simbody's steppers impose it, this one would leave the link still.
  SimTK::MultibodySystem turning;
  SimTK::SimbodyMatterSubsystem turning_matter(turning);
  SimTK::MobilizedBody::Pin crank(turning_matter.Ground(), SimTK::Transform(),
                                  SimTK::Body::Rigid(SimTK::MassProperties(1.0, SimTK::Vec3(0.1, 0, 0), SimTK::Inertia(1))),
                                  SimTK::Transform());
  SimTK::Motion::Steady(crank, 2.0);
  turning.realizeTopology();
  fp::MuscleRosenbrockIntegrator turning_integ(turning, {}, 1e-6);
  expect_refused_at_initialize(turning_integ, turning.getDefaultState(), "prescribed motion");
  EXPECT_THROW(fp::MuscleRosenbrockIntegrator(system, {}, 0.0), std::invalid_argument);
  EXPECT_THROW(fp::MuscleRosenbrockIntegrator(system, {}, 1.5), std::invalid_argument);
  EXPECT_THROW(integ.setFixedStepSize(-1.0), std::invalid_argument);
  EXPECT_THROW(integ.advanceTo(1.0), std::logic_error);  // never initialized
}

TEST(MuscleRosenbrock, IntegratorNamesRoundTrip) {
  for (auto kind : {fp::IntegratorKind::RungeKuttaMerson, fp::IntegratorKind::CPodesBdf, fp::IntegratorKind::MuscleRosenbrock})
    EXPECT_EQ(fp::integrator_from_name(fp::integrator_name(kind)), kind);
  try {
    fp::integrator_from_name("euler");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("euler"), std::string::npos);
  }
}

TEST(Stepper, ContractIsTheSameForEveryIntegrator) {
  // updState() + inputsChanged(): edits of inputs and of continuous states are taken over, also
  // after several updState() calls; non-finite times are rejected by name.
  const auto arm = flatsos::test::load_arm();
  const SimTK::State s0 = stiff_start(*arm);
  for (auto kind : {fp::IntegratorKind::RungeKuttaMerson, fp::IntegratorKind::CPodesBdf, fp::IntegratorKind::MuscleRosenbrock}) {
    auto stepper = fp::make_stepper(*arm, kind, 1e-7);
    stepper->initialize(s0);
    ASSERT_TRUE(stepper->advanceTo(0.02)) << fp::integrator_name(kind);
    const double q_before = arm->jointAngles(stepper->state())[0];
    arm->muscle(0).setExcitation(stepper->updState(), 0.9);
    arm->setJointSpeeds(stepper->updState(), Eigen::Vector2d(0.5, -0.5));  // a second call keeps the first edit
    stepper->inputsChanged();
    EXPECT_EQ(arm->muscle(0).getExcitation(stepper->state()), 0.9) << fp::integrator_name(kind);
    EXPECT_EQ(arm->jointSpeeds(stepper->state())[0], 0.5) << fp::integrator_name(kind);
    ASSERT_TRUE(stepper->advanceTo(0.021)) << fp::integrator_name(kind);
    // Started from the edited speeds: the shoulder moved up by about 0.5 rad/s x 1 ms.
    EXPECT_NEAR(arm->jointAngles(stepper->state())[0] - q_before, 5e-4, 5e-5) << fp::integrator_name(kind);
    EXPECT_THROW(stepper->advanceTo(std::nan("")), std::invalid_argument);
    EXPECT_THROW(stepper->advanceTo(1.0, {0.5, std::nan("")}, [](const SimTK::State&) {}), std::invalid_argument);
  }
}

TEST(MuscleRosenbrock, RejectsAMuscleListedTwice) {
  const auto arm = flatsos::test::load_arm();
  fp::MuscleRosenbrockIntegrator integ(arm->system(), {arm->muscle(1), arm->muscle(1)}, 1e-6);
  try {
    integ.initialize(arm->defaultState());
    FAIL() << "a muscle listed twice was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("posterior_deltoid' is listed twice"), std::string::npos) << e.what();
  }
}
