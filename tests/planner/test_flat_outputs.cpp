// Flat outputs: Assumption 1 is enforced with named conditions, and the forward and inverse maps
// are inverses (along a Simbody simulation, and along a planned flat trajectory).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "flatsos/planner/joint_paths.hpp"
#include "flatsos/planner/numerics/bspline.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"
#include "scenario_fixture.hpp"

namespace fpl = flatsos::planner;
namespace fp = flatsos::plugin;

namespace {
class Sinusoid : public fp::ExcitationSignal {
 public:
  Sinusoid(double mean, double amp, double hz, double phase) : mean_(mean), amp_(amp), hz_(hz), phase_(phase) {}
  double value(double t) const override { return mean_ + amp_ * std::sin(2 * flatsos::test::kPi * hz_ * t + phase_); }

 private:
  double mean_, amp_, hz_, phase_;
};

void expect_assumption_failure(const Eigen::MatrixXd& A, const Eigen::MatrixXd& E, const std::string& text) {
  try {
    fpl::FlatOutputMap::checkAssumption1(A, E);
    ADD_FAILURE() << "accepted: " << text;
  } catch (const fpl::FlatnessError& e) {
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
  }
}
}  // namespace

TEST(FlatOutputs, ArmSatisfiesAssumption1AndCInverseSplits) {
  flatsos::test::ArmPlanning arm;
  const Eigen::MatrixXd I = arm.flat.C() * (Eigen::MatrixXd(6, 6) << arm.flat.Ctau(), arm.flat.CY()).finished();
  EXPECT_TRUE(I.isIdentity(1e-12));
  // Paper appendix: C_Y 1 = 1 - C_tau s_tau > 0.
  EXPECT_GT((arm.flat.CY().rowwise().sum()).minCoeff(), 0.0);
}

TEST(FlatOutputs, Assumption1ViolationsAreNamed) {
  flatsos::test::ArmPlanning arm;
  const Eigen::MatrixXd A = arm.flat.A();
  Eigen::MatrixXd E = arm.flat.E();
  expect_assumption_failure(A, E.topRows(3), "(m - N) x m");
  Eigen::MatrixXd singular = E;
  singular.row(3) = E.row(2);
  expect_assumption_failure(A, singular, "condition 1: C = [A; E] is singular");
  Eigen::MatrixXd unnormalized = E;
  unnormalized(3, 4) = 0.9;
  expect_assumption_failure(A, unnormalized, "condition 2: row 3 of E sums to 0.9");
  // One joint, two muscles: A = [1, -3], E = [-1, 2] has C_Y = [-3, -1] < 0.
  expect_assumption_failure((Eigen::MatrixXd(1, 2) << 1, -3).finished(), (Eigen::MatrixXd(1, 2) << -1, 2).finished(),
                            "condition 3");
}

TEST(FlatOutputs, ForwardThenInverseClosesAlongASimbodySimulation) {
  flatsos::test::ArmPlanning arm;
  const auto& model = *arm.model;
  SimTK::State s = model.defaultState();
  model.setJointAngles(s, Eigen::Vector2d(0.0, flatsos::test::deg(10)));
  model.setJointSpeeds(s, Eigen::Vector2d(0.001, 0.002));
  fp::equilibrate_tendons(model, s, flatsos::test::paper_a0());
  for (int j = 0; j < 6; ++j)
    model.muscle(j).setExcitationSignal(s, std::make_shared<Sinusoid>(0.35, 0.25, 0.8 + 0.3 * j, 0.5 * j));
  fp::SimulationOptions o;
  o.duration_s = 1.0;
  o.accuracy = 1e-10;
  o.report_interval_s = 0.1;
  const auto sim = fp::simulate(model, s, o);
  ASSERT_TRUE(sim.finite);
  const auto q0 = sim.states.column("/jointset/shoulder/shoulder/value");
  EXPECT_GT(std::abs(q0.back() - q0.front()), 0.05);  // the arm really moves
  for (const auto& row : sim.states.rows) {
    fpl::MuscleState ms;
    ms.q_rad = Eigen::Vector2d(row[1], row[3]);
    ms.qd_rad_per_s = Eigen::Vector2d(row[2], row[4]);
    ms.activation.resize(6);
    ms.tendon_length_m.resize(6);
    for (int j = 0; j < 6; ++j) {
      ms.activation[j] = row[static_cast<std::size_t>(5 + 5 * j)];
      ms.tendon_length_m[j] = row[static_cast<std::size_t>(5 + 5 * j + 1)];
    }
    const fpl::FlatState y = arm.flat.forward(ms);
    const fpl::MusclePoint back = arm.flat.inverse(y.q, y.Y);
    for (int j = 0; j < 6; ++j) {
      EXPECT_NEAR(back.tendon_length_m[j], ms.tendon_length_m[j], 1e-8 * ms.tendon_length_m[j]) << "t " << row[0];
      EXPECT_NEAR(back.activation[j], ms.activation[j], 1e-8 * ms.activation[j]) << "t " << row[0] << " muscle " << j;
    }
  }
}

TEST(FlatOutputs, ForwardMapAccelerationAndJerkAgreeWithSimbody) {
  flatsos::test::ArmPlanning arm;
  const auto& model = *arm.model;
  SimTK::State s = model.defaultState();
  model.setJointAngles(s, Eigen::Vector2d(0.3, 0.5));
  model.setJointSpeeds(s, Eigen::Vector2d(0.4, -0.2));
  Eigen::VectorXd a(6);
  a << 0.3, 0.1, 0.5, 0.2, 0.4, 0.6;
  fp::equilibrate_tendons(model, s, a);
  model.setExcitations(s, a);
  auto state_of = [&](const SimTK::State& st) { return fpl::muscle_state_of(model, st); };
  const fpl::FlatState y = arm.flat.forward(state_of(s));
  model.system().realize(s, SimTK::Stage::Acceleration);
  EXPECT_NEAR(y.q(0, 2), s.getUDot()[0], 1e-10 * (1 + std::abs(s.getUDot()[0])));
  EXPECT_NEAR(y.q(1, 2), s.getUDot()[1], 1e-10 * (1 + std::abs(s.getUDot()[1])));
  // q''' against a central difference of Simbody's accelerations along the simulated motion.
  fp::SimulationOptions o;
  // The tendon states react within milliseconds (stiff tendons), so the step must be tiny.
  const double dt = 1e-5;
  o.duration_s = dt;
  o.accuracy = 1e-12;
  o.report_interval_s = dt;
  const auto sim = fp::simulate(model, s, o);
  const SimTK::State& end = sim.final_state;
  model.system().realize(end, SimTK::Stage::Acceleration);
  const fpl::FlatState y_end = arm.flat.forward(state_of(end));
  // The secant of qdd over dt equals the mean of q''' at both ends to O(dt^2) (trapezoid rule).
  for (int i = 0; i < 2; ++i) {
    const double secant = (y_end.q(i, 2) - y.q(i, 2)) / dt;
    const double mid = 0.5 * (y.q(i, 3) + y_end.q(i, 3));
    EXPECT_NEAR(mid, secant, 1e-4 * (1 + std::abs(secant))) << "joint " << i;
  }
}

TEST(FlatOutputs, InverseThenForwardReproducesAPlannedFlatTrajectory) {
  flatsos::test::ArmPlanning arm;
  const auto plan = fpl::plan_open_loop(arm.flat, flatsos::test::open_loop_initial_state(*arm.model),
                                        flatsos::test::open_loop_options());
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
  for (double t : {0.0, 0.37, 1.2, 2.5, 2.99}) {
    const fpl::Jet qj = plan.jointJet(t), yj = plan.flatOutputJet(t);
    const fpl::MusclePoint mp = arm.flat.inverse(qj, yj);
    ASSERT_TRUE(mp.inDomain());
    const fpl::FlatState y = arm.flat.forward({qj.col(0), qj.col(1), mp.tendon_length_m, mp.activation});
    for (int i = 0; i < 2; ++i)
      for (int k = 0; k < 4; ++k)
        EXPECT_NEAR(y.q(i, k), qj(i, k), 1e-8 * (1 + std::abs(qj(i, k)))) << "t " << t << " joint " << i << " order " << k;
    for (int l = 0; l < 4; ++l)
      for (int k = 0; k < 2; ++k)
        EXPECT_NEAR(y.Y(l, k), yj(l, k), 1e-8 * (1 + std::abs(yj(l, k)))) << "t " << t << " output " << l << " order " << k;
  }
}

TEST(FlatOutputs, TorqueJetsAlongASplinePathAreExactAtItsEndsAndShortSpans) {
  // A degree-8 spline on spans from 21 ms growing by 1.4: differences in time straddle its knots
  // (where it is only C7) and its ends; torque_jets_on_grid must give the exact jets there.
  flatsos::test::ArmPlanning arm;
  const fpl::BSplineBasis basis = fpl::BSplineBasis::geometric(8, 12, 3.0, 1.4);
  Eigen::MatrixXd c(2, basis.size());
  for (int i = 0; i < basis.size(); ++i) c(0, i) = 1.5 * std::sin(0.7 * i), c(1, i) = 0.2 + std::cos(0.9 * i);
  const fpl::JointPath path = fpl::JointPath::fromSpline(fpl::SplineTrajectory(basis, c));
  fp::ModelWorkspace ws = arm.flat.makeWorkspace();
  const int count = 301;
  const double h = 3.0 / (count - 1);
  const auto jets = fpl::torque_jets_on_grid(arm.flat, ws, path, h, count);
  const auto differences = arm.flat.torqueJetsOnGrid(ws, [&](double t) { return path.jet(t, 4); }, 0.0, h, count);
  ASSERT_EQ(jets.size(), static_cast<std::size_t>(count));
  double worst_difference = 0.0;
  for (int i = 0; i < count; ++i) {
    const fpl::TorqueJet pointwise = arm.flat.torqueJet(ws, path.jet(h * i, 5));
    const double scale = 1.0 + pointwise.tau.cwiseAbs().maxCoeff();
    EXPECT_LT((jets[i].tau - pointwise.tau).cwiseAbs().maxCoeff(), 1e-12 * scale) << "t = " << h * i;
    worst_difference = std::max(worst_difference, (differences[i].tau - pointwise.tau).cwiseAbs().maxCoeff() / scale);
  }
  // What the differences would have given: far off (the reason for the exact jets).
  EXPECT_GT(worst_difference, 1e-3);
}

TEST(FlatOutputs, TorqueJetsOnAGridEqualThePointwiseJets) {
  flatsos::test::ArmPlanning arm;
  const auto plan = fpl::plan_open_loop(arm.flat, flatsos::test::open_loop_initial_state(*arm.model),
                                        flatsos::test::open_loop_options());
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved);
  // h = 0.3 s is refined internally to 10 ms; h = 5 ms is used as is.
  for (const double h : {0.3, 0.005}) {
    const int count = 11;
    fp::ModelWorkspace ws = arm.flat.makeWorkspace();
    const auto jets = arm.flat.torqueJetsOnGrid(ws, [&](double t) { return plan.path.jet(t, 4); }, 0.2, h, count);
    ASSERT_EQ(jets.size(), 11u);
    for (int i = 0; i < count; ++i) {
      const fpl::TorqueJet pointwise = arm.flat.torqueJet(plan.jointJet(0.2 + h * i));
      EXPECT_LT((jets[i].tau - pointwise.tau).cwiseAbs().maxCoeff(), 1e-6 * (1 + pointwise.tau.cwiseAbs().maxCoeff()))
          << "h " << h << " i " << i;
    }
  }
}
