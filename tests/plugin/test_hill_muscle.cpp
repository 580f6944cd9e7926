// The Simbody force element: state access, excitation input, and robustness where the forward
// model is singular (a -> 0, slack tendon, extreme excitations): never NaN or Inf.
#include <gtest/gtest.h>

#include "finite_difference.hpp"

#include <cmath>
#include <limits>
#include <thread>
#include <vector>

#include "arm_fixture.hpp"
#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"
#include "flatsos/plugin/model/static_equilibrium.hpp"

namespace fp = flatsos::plugin;
using flatsos::test::ConstantSignal;
using flatsos::test::deg;
using flatsos::test::paper_state;

namespace {

// Every state finite and physically bounded along the run: activations in [0, 1], tendons
// never shorter than half their slack length, joint speeds below 100 rad/s.
void expect_bounded(const fp::MusculoskeletalModel& arm, const fp::SimulationResult& r) {
  ASSERT_TRUE(r.finite) << r.message;
  for (const auto& row : r.states.rows)
    for (double v : row) ASSERT_TRUE(std::isfinite(v));
  for (int j = 0; j < arm.numMuscles(); ++j) {
    const auto& name = arm.description().muscles[j].parameters.name;
    const double slack = arm.description().muscles[j].parameters.tendon_slack_length_m;
    for (double a : r.states.column("/forceset/" + name + "/activation")) {
      EXPECT_GE(a, 0.0);
      EXPECT_LE(a, 1.0);
    }
    for (double ls : r.states.column("/forceset/" + name + "/tendon_length")) EXPECT_GT(ls, 0.5 * slack);
  }
  for (const auto& joint : arm.description().joints)
    for (double qd : r.states.column("/jointset/" + joint.name + "/" + joint.coordinateName() + "/speed")) EXPECT_LT(std::abs(qd), 100.0);
}


}  // namespace

TEST(HillMuscle, StateAccessorsRoundTripAndRejectBadValues) {
  const auto arm = flatsos::test::load_arm();
  SimTK::State s = arm->defaultState();
  const auto& biceps = arm->muscle(2);
  biceps.setActivation(s, 0.3);
  biceps.setTendonLength(s, 0.235);
  EXPECT_EQ(biceps.getActivation(s), 0.3);
  EXPECT_EQ(biceps.getTendonLength(s), 0.235);
  EXPECT_THROW(biceps.setActivation(s, 1.5), std::invalid_argument);
  EXPECT_THROW(biceps.setActivation(s, -0.1), std::invalid_argument);
  EXPECT_THROW(biceps.setActivation(s, std::nan("")), std::invalid_argument);
  EXPECT_THROW(biceps.setTendonLength(s, -0.2), std::invalid_argument);
  EXPECT_THROW(biceps.setExcitation(s, std::nan("")), std::invalid_argument);
  try {
    biceps.setActivation(s, 2.0);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("biceps"), std::string::npos);
  }
}

TEST(HillMuscle, ExcitationIsClampedAndSignalsOverrideHeldValues) {
  const auto arm = flatsos::test::load_arm();
  SimTK::State s = arm->defaultState();
  const auto& m = arm->muscle(0);
  m.setExcitation(s, 1.7);
  EXPECT_EQ(m.getExcitation(s), 1.0);
  EXPECT_EQ(m.getUnclampedExcitation(s), 1.7);
  m.setExcitation(s, -0.2);
  EXPECT_EQ(m.getExcitation(s), 0.0);
  m.setExcitationSignal(s, std::make_shared<fp::PiecewiseLinearSignal>(std::vector<double>{0.0, 1.0},
                                                                       std::vector<double>{0.2, 0.6}));
  s.updTime() = 0.25;
  EXPECT_NEAR(m.getExcitation(s), 0.3, 1e-15);
  m.setExcitationSignal(s, std::make_shared<ConstantSignal>(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_EQ(m.getExcitation(s), 0.0);  // a NaN signal drives nothing rather than poisoning the run
  m.setExcitation(s, 0.4);             // a held value replaces the signal
  EXPECT_EQ(m.getExcitation(s), 0.4);
}

TEST(HillMuscle, APolynomialPieceIsHeldByValueInTheState) {
  const auto arm = flatsos::test::load_arm();
  SimTK::State s = arm->defaultState();
  const auto& m = arm->muscle(0);
  fp::ExcitationPolynomial piece;  // n = 0.2 + 0.4 s - 0.1 s^2 over [1, 1.5] s
  piece.coefficients = {0.2, 0.4, -0.1};
  piece.count = 3;
  piece.start_time_s = 1.0;
  piece.duration_s = 0.5;
  m.setExcitationPolynomial(s, piece);
  s.updTime() = 1.25;
  EXPECT_NEAR(m.getExcitation(s), 0.2 + 0.4 * 0.5 - 0.1 * 0.25, 1e-15);
  s.updTime() = 0.3;
  EXPECT_NEAR(m.getExcitation(s), 0.2, 1e-15);  // held before the piece
  s.updTime() = 9.0;
  EXPECT_NEAR(m.getExcitation(s), 0.5, 1e-15);  // and after it
  // Each State keeps its own piece: a copy is not changed by what is set on the original.
  const SimTK::State copy = s;
  m.setExcitationPolynomial(s, fp::ExcitationPolynomial::constant(0.9));
  EXPECT_EQ(m.getExcitation(s), 0.9);
  EXPECT_NEAR(m.getExcitation(copy), 0.5, 1e-15);
  // A signal takes precedence while set; a piece replaces it.
  m.setExcitationSignal(s, std::make_shared<ConstantSignal>(0.1));
  EXPECT_EQ(m.getExcitation(s), 0.1);
  m.setExcitationPolynomial(s, piece);
  EXPECT_NEAR(m.getExcitation(s), 0.5, 1e-15);
  // Bad pieces name the muscle and what is wrong.
  auto bad = piece;
  bad.count = 0;
  EXPECT_THROW(m.setExcitationPolynomial(s, bad), std::invalid_argument);
  bad = piece;
  bad.coefficients[1] = std::nan("");
  try {
    m.setExcitationPolynomial(s, bad);
    ADD_FAILURE() << "a NaN coefficient was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(m.getParameters().name), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("coefficient 1"), std::string::npos) << e.what();
  }
  bad = piece;
  bad.duration_s = 0.0;
  EXPECT_THROW(m.setExcitationPolynomial(s, bad), std::invalid_argument);
}

TEST(HillMuscleRobustness, ZeroExcitationForSecondsStaysFiniteAndBounded) {
  const auto arm = flatsos::test::load_arm();
  SimTK::State s = paper_state(*arm);
  arm->setExcitations(s, Eigen::VectorXd::Zero(6));
  fp::SimulationOptions o;
  o.duration_s = 3.0;
  o.report_interval_s = 0.05;
  // Once activations fall below the floor the tendon ODE is stiff (rates ~1e6/s): Runge-Kutta-
  // Merson needs ~5e5 steps per simulated second here, the implicit BDF ~1e3. BDF needs a tight
  // accuracy: at 1e-6 and 1e-7 its error control let slack tendons drift far below slack length
  // (measured), at 1e-8 they stay within round-off of it.
  o.accuracy = 1e-8;
  o.integrator = fp::IntegratorKind::CPodesBdf;
  const auto r = fp::simulate(*arm, s, o);
  expect_bounded(*arm, r);
  // Deactivation decays with T_deact = 0.04 s: after 3 s every activation is ~0.
  EXPECT_LT(arm->activations(r.final_state).maxCoeff(), 1e-6);
  // With no muscle force the arm falls and hangs down: the shoulder angle goes below 0.
  EXPECT_LT(r.states.column("/jointset/shoulder/shoulder/value").back(), -0.5);
}

// Simbody realizes forces through one task object per System, so two threads simulating States
// of one model at once raced (their runs differed from a single thread's, silently). They now
// take turns (integration/system_dynamics_lock.hpp) and each gets exactly the single-threaded
// run, with Simbody's integrator and with the muscle Rosenbrock method.
TEST(Simulation, TwoThreadsSimulatingOneModelAtOnceGetTheSingleThreadedRun) {
  for (const fp::IntegratorKind integrator : {fp::IntegratorKind::RungeKuttaMerson, fp::IntegratorKind::MuscleRosenbrock}) {
    SCOPED_TRACE(fp::integrator_name(integrator));
    const auto simulate_from_rest = [integrator](const fp::MusculoskeletalModel& arm) {
      SimTK::State s = paper_state(arm);
      arm.setExcitations(s, Eigen::VectorXd::Constant(6, 0.3));
      fp::SimulationOptions o;
      o.duration_s = 0.3;
      o.report_interval_s = 0.1;
      o.accuracy = 1e-8;
      o.integrator = integrator;
      return fp::simulate(arm, s, o);
    };
    const auto single = simulate_from_rest(*flatsos::test::load_arm());
    ASSERT_TRUE(single.finite) << single.message;
    const auto shared = flatsos::test::load_arm();
    std::vector<fp::SimulationResult> runs(2);
    std::vector<std::thread> threads;
    for (std::size_t i = 0; i < runs.size(); ++i) threads.emplace_back([&, i] { runs[i] = simulate_from_rest(*shared); });
    for (auto& t : threads) t.join();
    for (const auto& r : runs) {
      ASSERT_TRUE(r.finite) << r.message;
      ASSERT_EQ(r.states.rows.size(), single.states.rows.size());
      EXPECT_EQ(r.states.rows.back(), single.states.rows.back());
    }
    // The arm moved: the run is not the initial state copied through.
    const auto shoulder = single.states.column("/jointset/shoulder/shoulder/value");
    const auto elbow = single.states.column("/jointset/elbow/elbow/value");
    EXPECT_GT(std::abs(shoulder.back() - shoulder.front()) + std::abs(elbow.back() - elbow.front()), 0.05);
  }
}

namespace {
// The zero-excitation fall above, to its first 0.5 s, with the step limit.
fp::SimulationResult fall_with_step_limit(const fp::MusculoskeletalModel& arm, fp::IntegratorKind integrator, long max_steps) {
  SimTK::State s = paper_state(arm);
  arm.setExcitations(s, Eigen::VectorXd::Zero(6));
  fp::SimulationOptions o;
  o.duration_s = 0.5;
  o.report_interval_s = 0.01;
  o.accuracy = 1e-8;
  o.integrator = integrator;
  o.max_steps = max_steps;
  return fp::simulate(arm, s, o);
}
}  // namespace

// Where the muscles' states are stiff, the explicit method's replay can run for hours (an
// unstable plan replayed open loop: the arm falls, its tendons load at tiny activation). The
// step limit ends it with the rows so far and a reason, and leaves the trajectory alone.
TEST(SimulationStepLimit, AStiffExplicitRunStopsAtTheLimitWithItsRowsAndTheReason) {
  const auto arm = flatsos::test::load_arm();
  const long limit = 4000;
  const auto r = fall_with_step_limit(*arm, fp::IntegratorKind::RungeKuttaMerson, limit);
  EXPECT_TRUE(r.step_limit_reached);
  EXPECT_TRUE(r.finite);
  EXPECT_FALSE(r.completed());
  EXPECT_EQ(r.integrator_steps, limit);
  for (const char* part : {"integration stopped at t = ", "the step limit", "rosenbrock or bdf"})
    EXPECT_NE(r.message.find(part), std::string::npos) << part << " not in: " << r.message;
  // Stopped at the limit well before the end (between report times), every row so far kept and
  // finite, and a last row where it stopped.
  ASSERT_GE(r.states.rows.size(), 2u);
  const double stopped_s = r.states.rows.back()[0];
  EXPECT_LT(stopped_s, 0.5 - 0.01);
  EXPECT_NEAR(stopped_s, r.final_state.getTime(), 1e-12);
  EXPECT_EQ(r.controls.rows.size(), r.states.rows.size());
  for (const auto& row : r.states.rows)
    for (double v : row) EXPECT_TRUE(std::isfinite(v));
  // A higher limit goes further along the same trajectory: the limit only says where to stop
  // (the report rows before the stop are the same).
  const auto further = fall_with_step_limit(*arm, fp::IntegratorKind::RungeKuttaMerson, 2 * limit);
  ASSERT_GT(further.states.rows.size(), r.states.rows.size());
  for (std::size_t k = 0; k + 1 < r.states.rows.size(); ++k)
    EXPECT_EQ(further.states.rows[k], r.states.rows[k]) << "row " << k;
}

// The limit holds inside a report interval too: a run reported only at its end, or asked for an
// absurd duration, stops at the limit instead of integrating for hours.
TEST(SimulationStepLimit, TheLimitHoldsBetweenReportTimesForEveryIntegrator) {
  const auto arm = flatsos::test::load_arm();
  for (const auto kind : {fp::IntegratorKind::RungeKuttaMerson, fp::IntegratorKind::CPodesBdf,
                          fp::IntegratorKind::MuscleRosenbrock}) {
    SimTK::State s = paper_state(*arm);
    fp::SimulationOptions o;
    o.duration_s = 1e30;
    o.report_interval_s = 1e29;
    o.integrator = kind;
    o.max_steps = 250;
    const auto r = fp::simulate(*arm, s, o);
    EXPECT_TRUE(r.step_limit_reached) << fp::integrator_name(kind);
    EXPECT_EQ(r.integrator_steps, 250) << fp::integrator_name(kind);
    EXPECT_EQ(r.states.rows.size(), 2u);  // the start, and where it stopped
    EXPECT_NEAR(r.states.rows.back()[0], r.final_state.getTime(), 1e-12);
  }
}

TEST(SimulationStepLimit, AnImplicitIntegratorFinishesTheSameRunWithinIt) {
  const auto arm = flatsos::test::load_arm();
  const auto r = fall_with_step_limit(*arm, fp::IntegratorKind::CPodesBdf, 4000);
  EXPECT_TRUE(r.completed()) << r.message;
  EXPECT_FALSE(r.step_limit_reached);
  EXPECT_TRUE(r.message.empty()) << r.message;
  EXPECT_LT(r.integrator_steps, 4000);
  EXPECT_NEAR(r.states.rows.back()[0], 0.5, 1e-12);
  // No limit (0): the same run, step for step.
  const auto unlimited = fall_with_step_limit(*arm, fp::IntegratorKind::CPodesBdf, 0);
  EXPECT_TRUE(unlimited.completed());
  EXPECT_EQ(unlimited.integrator_steps, r.integrator_steps);
  EXPECT_EQ(unlimited.states.rows.back(), r.states.rows.back());
  // A limit the whole run just reaches (at its last row, the end): complete, not stopped.
  const auto exactly = fall_with_step_limit(*arm, fp::IntegratorKind::CPodesBdf, r.integrator_steps);
  EXPECT_TRUE(exactly.completed()) << exactly.message;
  EXPECT_EQ(exactly.states.rows.size(), r.states.rows.size());
}

TEST(HillMuscleRobustness, SlackTendonsAndActivationAtZeroStayFinite) {
  const auto arm = flatsos::test::load_arm();
  SimTK::State s = arm->defaultState();
  arm->setJointAngles(s, Eigen::Vector2d(deg(30), deg(40)));
  Eigen::VectorXd slack(6);
  for (int j = 0; j < 6; ++j) slack[j] = 0.9 * arm->description().muscles[j].parameters.tendon_slack_length_m;
  arm->setTendonLengths(s, slack);
  arm->setActivations(s, Eigen::VectorXd::Zero(6));
  arm->setExcitations(s, Eigen::VectorXd::Constant(6, 0.5));
  arm->system().realize(s, SimTK::Stage::Acceleration);
  for (int j = 0; j < 6; ++j) {
    EXPECT_EQ(arm->muscle(j).getTendonForce(s), 0.0);
    // A slack tendon: z = 0, the fiber shortens at Vmax and takes up the slack.
    EXPECT_GT(arm->muscle(j).getTendonLengthDerivative(s), 0.0);
  }
  fp::SimulationOptions o;
  o.duration_s = 1.0;
  o.accuracy = 1e-6;
  o.report_interval_s = 0.05;
  expect_bounded(*arm, fp::simulate(*arm, s, o));
}

TEST(HillMuscleRobustness, LoadedTendonAtTheActivationFloorStaysFinite) {
  const auto arm = flatsos::test::load_arm();
  SimTK::State s = paper_state(*arm);
  arm->setActivations(s, Eigen::VectorXd::Zero(6));  // loaded tendons, no activation: z >> gmax
  arm->setExcitations(s, Eigen::VectorXd::Zero(6));
  arm->system().realize(s, SimTK::Stage::Acceleration);
  for (int j = 0; j < 6; ++j) EXPECT_TRUE(std::isfinite(arm->muscle(j).getTendonLengthDerivative(s)));
  fp::SimulationOptions o;
  o.duration_s = 0.5;
  o.accuracy = 1e-8;
  o.report_interval_s = 0.05;
  o.integrator = fp::IntegratorKind::CPodesBdf;
  const auto bdf = fp::simulate(*arm, s, o);
  expect_bounded(*arm, bdf);
  // The explicit and the implicit integrator agree on this stiff run (checked on its first
  // 0.1 s, where the explicit one is still affordable).
  o.duration_s = 0.1;
  o.integrator = fp::IntegratorKind::RungeKuttaMerson;
  const auto rkm = fp::simulate(*arm, s, o);
  expect_bounded(*arm, rkm);
  const auto q_rkm = rkm.states.column("/jointset/shoulder/shoulder/value");
  const auto q_bdf = bdf.states.column("/jointset/shoulder/shoulder/value");
  const auto ls_rkm = rkm.states.column("/forceset/brachialis/tendon_length");
  const auto ls_bdf = bdf.states.column("/forceset/brachialis/tendon_length");
  for (std::size_t k = 0; k < q_rkm.size(); ++k) {
    EXPECT_NEAR(q_rkm[k], q_bdf[k], 1e-5) << k;
    EXPECT_NEAR(ls_rkm[k], ls_bdf[k], 1e-8) << k;
  }
}

TEST(HillMuscleRobustness, FullExcitationStaysFiniteAndBounded) {
  const auto arm = flatsos::test::load_arm();
  SimTK::State s = paper_state(*arm);
  arm->setExcitations(s, Eigen::VectorXd::Ones(6));
  fp::SimulationOptions o;
  o.duration_s = 1.0;
  o.accuracy = 1e-6;
  o.report_interval_s = 0.05;
  const auto r = fp::simulate(*arm, s, o);
  expect_bounded(*arm, r);
  EXPECT_GT(arm->activations(r.final_state).minCoeff(), 0.99);
}

TEST(StaticEquilibrium, ClearErrorsWhereNoEquilibriumExists) {
  const auto arm = flatsos::test::load_arm();
  const auto& p = arm->muscle(5).getParameters();  // brachialis, slack length 0.0175 m
  EXPECT_THROW(fp::static_equilibrium_tendon_length(p, 0.15, 1.5), std::domain_error);
  EXPECT_THROW(fp::static_equilibrium_tendon_length(p, 0.15, std::nan("")), std::domain_error);
  try {
    fp::static_equilibrium_tendon_length(p, 0.01, 0.3);
    ADD_FAILURE();
  } catch (const std::domain_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("brachialis"), std::string::npos) << msg;
    EXPECT_NE(msg.find("slack"), std::string::npos) << msg;
  }
}

TEST(StaticEquilibrium, SolvesTheBalanceToRoundOff) {
  const auto arm = flatsos::test::load_arm();
  for (int j = 0; j < arm->numMuscles(); ++j) {
    const auto& p = arm->muscle(j).getParameters();
    for (double a : {0.0, 0.001, 0.1, 0.5, 1.0}) {
      const double length = p.tendon_slack_length_m + 0.9 * p.optimal_fiber_length_m;
      const double ls = fp::static_equilibrium_tendon_length(p, length, a);
      const double capacity = flatsos::muscles::effective_activation(p, a) * p.max_isometric_force_N *
                              flatsos::muscles::force_length(p, length - ls);
      EXPECT_NEAR(flatsos::muscles::tendon_force(p, ls), capacity, 1e-9 * p.max_isometric_force_N) << j << " " << a;
    }
  }
}

TEST(HillMuscle, YIndexAndPartialsForIntegrators) {
  const auto arm = flatsos::test::load_arm();
  SimTK::State s = paper_state(*arm);
  arm->setActivations(s, Eigen::VectorXd::Constant(6, 0.002));
  arm->system().realize(s, SimTK::Stage::Acceleration);
  for (int j = 0; j < arm->numMuscles(); ++j) {
    const auto& m = arm->muscle(j);
    const int i = m.getTendonLengthYIndex(s);
    ASSERT_GE(i, 0);
    ASSERT_LT(i + 1, s.getNY());
    EXPECT_EQ(s.getY()[i], m.getTendonLength(s));
    EXPECT_EQ(s.getY()[i + 1], m.getActivation(s));
    EXPECT_EQ(s.getYDot()[i], m.getTendonLengthDerivative(s));
    EXPECT_EQ(s.getYDot()[i + 1], m.getActivationDerivative(s));
    // The partials equal finite differences of the muscle's own state derivative in the State.
    // Entry `of` of YDot as a function of state entry `which` (the others as in s).
    auto ydot = [&](int of, int which) {
      return [&, of, which](double value) {
        SimTK::State t = s;
        t.updY()[i + which] = value;
        arm->system().realize(t, SimTK::Stage::Acceleration);
        return t.getYDot()[i + of];
      };
    };
    const double ls = s.getY()[i], a = s.getY()[i + 1];
    const auto& p = m.getParameters();
    // Steps on the scales of the tendon's stretch (kept clear of slack) and of the activation.
    const double hl = flatsos::test::default_step(0.0, 1e-3 * p.tendon_slack_length_m);
    const double ha = flatsos::test::default_step(0.0, 1e-2 * a);
    const auto d = m.getTendonLengthDerivativePartials(s);
    EXPECT_MATCHES_FINITE_DIFFERENCE(d.d_tendon_length_per_s, flatsos::test::central_difference(ydot(0, 0), ls, hl)) << j;
    EXPECT_MATCHES_FINITE_DIFFERENCE(d.d_activation_m_per_s, flatsos::test::central_difference(ydot(0, 1), a, ha)) << j;
    EXPECT_MATCHES_FINITE_DIFFERENCE(m.getActivationDerivativePartial(s), flatsos::test::central_difference(ydot(1, 1), a, ha))
        << j;
  }
}
