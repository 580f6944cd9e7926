// Flatness with posture-dependent moment arms, C(q) = [R(q); E]: the tendon-force jet through
// the coupling's rates against finite differences in time of F(t) = C(q(t))^-1 [tau(t); Y(t)]
// solved here directly; the forward and inverse maps as inverses along a Simbody simulation of
// the shipped posture-dependent elbow (pennated, passive fibres); Assumption 1 checked over the
// joint ranges with the failing posture named; what needs constant moment arms refuses by name.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "finite_difference.hpp"
#include "flatsos/planner/motion_planner.hpp"
#include "flatsos/planner/rest_state.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"
#include <random>

#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/plugin/model/static_equilibrium.hpp"
#include "scenario_fixture.hpp"

namespace fpl = flatsos::planner;
namespace fp = flatsos::plugin;
using flatsos::test::central_difference;
using flatsos::test::deg;

namespace {

std::shared_ptr<const fp::MusculoskeletalModel> posture_dependent_elbow() {
  return fp::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) + "/models/elbow_posture_dependent.json");
}

// A joint motion, torques and flat outputs as polynomials of time (any smooth signals will do).
// d^order/dt^order of sum_k c_k t^k (cubic).
double cubic_derivative(const double (&c)[4], double t, int order) {
  double v = 0.0;
  for (int k = order; k < 4; ++k) {
    double f = 1.0;
    for (int i = 0; i < order; ++i) f *= k - i;
    v += c[k] * f * std::pow(t, k - order);
  }
  return v;
}
double q_of(double t, int order) {
  static const double c[4] = {0.6, 0.9, 0.7, -0.5};
  return cubic_derivative(c, t, order);
}
Eigen::Vector3d tau_jet(double t) { return {4.0 + 3.0 * t - 2.0 * t * t, 3.0 - 4.0 * t, -4.0}; }
Eigen::Matrix<double, 2, 3> y_jet(double t) {
  Eigen::Matrix<double, 2, 3> y;
  y << 300.0 + 80.0 * t * t, 160.0 * t, 160.0, 120.0 - 30.0 * t, -30.0, 0.0;
  return y;
}

// F(t) solved directly from C(q(t)) = [R(q(t)); E].
Eigen::VectorXd force_at(const fpl::FlatOutputMap& flat, double t) {
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(1, q_of(t, 0));
  Eigen::MatrixXd C(3, 3);
  C << flat.momentArms(q), flat.E();
  Eigen::VectorXd rhs(3);
  rhs << tau_jet(t)[0], y_jet(t).col(0);
  return C.fullPivLu().solve(rhs);
}

fpl::Jet joint_jet(double t, int orders) {
  fpl::Jet j(1, orders);
  for (int k = 0; k < orders; ++k) j(0, k) = q_of(t, k);
  return j;
}

}  // namespace

TEST(PostureDependentFlatness, TheForceJetIsTheTimeDerivativeOfCInverseAlongTheMotion) {
  const fpl::FlatOutputMap flat(posture_dependent_elbow());
  ASSERT_FALSE(flat.hasConstantMomentArms());
  auto jet_at = [&](double t) {
    const Eigen::Matrix<double, 1, 3> tau = tau_jet(t).transpose();
    return flat.forceJetMap(joint_jet(t, 3)).forceJet(tau, y_jet(t));
  };
  for (double t : {0.0, 0.4, 0.9}) {
    const Eigen::MatrixXd F = jet_at(t);
    const Eigen::VectorXd direct = force_at(flat, t);
    for (int j = 0; j < 3; ++j) {
      EXPECT_NEAR(F(j, 0), direct[j], 1e-12 * (1.0 + std::abs(direct[j]))) << "muscle " << j;
      // Each order against the finite difference of the one below (order 0 solved directly).
      EXPECT_MATCHES_FINITE_DIFFERENCE(F(j, 1), central_difference([&](double s) { return force_at(flat, s)[j]; }, t, 1e-4));
      EXPECT_MATCHES_FINITE_DIFFERENCE(F(j, 2), central_difference([&](double s) { return jet_at(s)(j, 1); }, t, 1e-4));
    }
    // The posture really matters here: the coupling's rates are not zero.
    const fpl::ForceJetMap map = flat.forceJetMap(joint_jet(t, 3));
    EXPECT_GT(map.W10.norm(), 1e-3);
  }
}

TEST(PostureDependentFlatness, TheForceJetBySolvesEqualsTheOneThroughCInverse) {
  // forceJet(q, tau, Y) solves with one LU; forceJetMap forms C^-1 and the coupling rates. The
  // elbow (3 muscles) and the sagittal leg (40 muscles, 37 flat outputs), at random points of
  // random motions.
  for (const char* file : {"elbow_posture_dependent.json", "sagittal_leg_r.json"}) {
    SCOPED_TRACE(file);
    const fpl::FlatOutputMap flat(fp::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) + "/models/" + file));
    const int n = flat.numJoints(), p = flat.numFlatOutputs();
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> u(-1.0, 1.0), share(0.2, 0.8);
    const fp::ModelDescription& d = flat.model().description();
    for (int trial = 0; trial < 20; ++trial) {
      fpl::Jet q(n, 3);
      for (int i = 0; i < n; ++i) {
        const auto& range = d.joints[static_cast<std::size_t>(i)].range_rad;
        q(i, 0) = range[0] + share(rng) * (range[1] - range[0]);
        q(i, 1) = 2.0 * u(rng);
        q(i, 2) = 10.0 * u(rng);
      }
      Eigen::MatrixXd tau(n, 3), Y(p, trial % 2 ? 3 : 2);
      for (auto& v : tau.reshaped()) v = 20.0 * u(rng);
      for (auto& v : Y.reshaped()) v = 100.0 + 50.0 * u(rng);
      const Eigen::MatrixXd by_solves = flat.forceJet(q, tau, Y), by_inverse = flat.forceJetMap(q).forceJet(tau, Y);
      EXPECT_LT((by_solves - by_inverse).cwiseAbs().maxCoeff(), 1e-9 * (1.0 + by_inverse.cwiseAbs().maxCoeff())) << trial;
    }
  }
}

TEST(PostureDependentFlatness, CYsRatesAreItsTimeDerivativesAlongTheMotion) {
  // flatOutputColumnRates (rank-N factors) against central differences in time of C_Y(q(t)) and
  // of the first rate, and against the coupling rates' products W10 C_Y, W20 C_Y; along random
  // quadratic motions of the elbow and of the sagittal leg (3 joints, 40 muscles).
  for (const char* file : {"elbow_posture_dependent.json", "sagittal_leg_r.json"}) {
    SCOPED_TRACE(file);
    const fpl::FlatOutputMap flat(fp::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) + "/models/" + file));
    const int n = flat.numJoints();
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0), share(0.3, 0.7);
    const fp::ModelDescription& d = flat.model().description();
    for (int trial = 0; trial < 5; ++trial) {
      Eigen::VectorXd q0(n), v(n), a(n);
      for (int i = 0; i < n; ++i) {
        const auto& range = d.joints[static_cast<std::size_t>(i)].range_rad;
        q0[i] = range[0] + share(rng) * (range[1] - range[0]);
        v[i] = u(rng);
        a[i] = 5.0 * u(rng);
      }
      const auto map_at = [&](double t) {
        fpl::Jet q(n, 3);
        q << q0 + t * v + 0.5 * t * t * a, v + t * a, a;
        return flat.forceJetMap(q);
      };
      const auto rates_at = [&](double t) {
        Eigen::MatrixXd cy1, cy2;
        map_at(t).flatOutputColumnRates(cy1, cy2);
        return std::make_pair(cy1, cy2);
      };
      const double h = 1e-5;
      const fpl::ForceJetMap map = map_at(0.0);
      const auto [cy1, cy2] = rates_at(0.0);
      ASSERT_GT(cy1.norm(), 1e-6);  // the posture moves C_Y here
      const Eigen::MatrixXd fd1 = (map_at(h).CY - map_at(-h).CY) / (2.0 * h);
      const Eigen::MatrixXd fd2 = (rates_at(h).first - rates_at(-h).first) / (2.0 * h);
      EXPECT_LT((cy1 - fd1).cwiseAbs().maxCoeff(), 1e-6 * (1.0 + cy1.cwiseAbs().maxCoeff())) << trial;
      EXPECT_LT((cy2 - fd2).cwiseAbs().maxCoeff(), 1e-5 * (1.0 + cy2.cwiseAbs().maxCoeff())) << trial;
      EXPECT_LT((cy1 - map.W10 * map.CY).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + cy1.cwiseAbs().maxCoeff())) << trial;
      EXPECT_LT((cy2 - map.W20 * map.CY).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + cy2.cwiseAbs().maxCoeff())) << trial;
    }
  }
}

TEST(PostureDependentFlatness, ConstantMomentArmsHaveNoCouplingRates) {
  flatsos::test::ArmPlanning arm;
  const fpl::ForceJetMap map = arm.flat.forceJetMap(fpl::Jet::Constant(2, 3, 0.4));
  EXPECT_FALSE(map.varies());
  EXPECT_EQ(map.Ctau, arm.flat.Ctau());
  EXPECT_EQ(map.CY, arm.flat.CY());
  Eigen::MatrixXd cy1, cy2;
  map.flatOutputColumnRates(cy1, cy2);
  EXPECT_EQ(cy1, Eigen::MatrixXd::Zero(map.CY.rows(), map.CY.cols()));
  EXPECT_EQ(cy2, Eigen::MatrixXd::Zero(map.CY.rows(), map.CY.cols()));
}

TEST(PostureDependentFlatness, AtAPostureAtRestTheMapDoesNotVary) {
  // No joint rates: R1 = R2 = 0, so every coupling rate is 0 and none is formed; C^-1 is the
  // posture's alone. An acceleration alone moves R2.
  const fpl::FlatOutputMap flat(posture_dependent_elbow());
  fpl::Jet at_rest = fpl::Jet::Zero(1, 3), accelerating = fpl::Jet::Zero(1, 3), moving(1, 3);
  at_rest(0, 0) = accelerating(0, 0) = moving(0, 0) = deg(60);
  accelerating(0, 2) = 3.0;
  moving << deg(60), 1.5, -2.0;
  const fpl::ForceJetMap rest = flat.forceJetMap(at_rest), q_only = flat.forceJetMap(at_rest.leftCols(1)),
                         accel = flat.forceJetMap(accelerating), move = flat.forceJetMap(moving);
  EXPECT_FALSE(rest.varies());
  EXPECT_FALSE(q_only.varies());
  EXPECT_TRUE(accel.varies());
  EXPECT_TRUE(move.varies());
  EXPECT_EQ(rest.Ctau, move.Ctau);
  EXPECT_EQ(rest.CY, move.CY);
  // The force jet at rest as the direct solves give it.
  const Eigen::MatrixXd tau = Eigen::RowVector3d(4.0, 3.0, -4.0), Y = y_jet(0.3);
  const Eigen::MatrixXd by_map = rest.forceJet(tau, Y), by_solves = flat.forceJet(at_rest, tau, Y);
  EXPECT_LT((by_map - by_solves).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + by_solves.cwiseAbs().maxCoeff()));
}

TEST(PostureDependentFlatness, ForwardThenInverseClosesAlongASimbodySimulation) {
  const auto model = posture_dependent_elbow();
  const fpl::FlatOutputMap flat(model);
  SimTK::State s = model->defaultState();
  model->setJointAngles(s, Eigen::VectorXd::Constant(1, deg(30)));
  const Eigen::Vector3d a0(0.2, 0.15, 0.1);
  fp::equilibrate_tendons(*model, s, a0);
  model->setExcitations(s, Eigen::Vector3d(0.35, 0.3, 0.2));
  fp::SimulationOptions o;
  o.duration_s = 0.6;
  o.accuracy = 1e-10;
  o.report_interval_s = 0.05;
  const auto sim = fp::simulate(*model, s, o);
  ASSERT_TRUE(sim.finite) << sim.message;
  const auto q = sim.states.column("/jointset/elbow/elbow_flexion/value");
  EXPECT_GT(std::abs(q.back() - q.front()), deg(10));  // the moment arms really change
  for (const auto& row : sim.states.rows) {
    fpl::MuscleState ms;
    ms.q_rad = Eigen::VectorXd::Constant(1, row[1]);
    ms.qd_rad_per_s = Eigen::VectorXd::Constant(1, row[2]);
    ms.activation.resize(3);
    ms.tendon_length_m.resize(3);
    for (int j = 0; j < 3; ++j) {
      ms.activation[j] = row[static_cast<std::size_t>(3 + 5 * j)];
      ms.tendon_length_m[j] = row[static_cast<std::size_t>(3 + 5 * j + 1)];
    }
    const fpl::FlatState y = flat.forward(ms);
    const fpl::MusclePoint back = flat.inverse(y.q, y.Y);
    for (int j = 0; j < 3; ++j) {
      EXPECT_NEAR(back.tendon_length_m[j], ms.tendon_length_m[j], 1e-10 * ms.tendon_length_m[j]) << "t " << row[0];
      EXPECT_NEAR(back.activation[j], ms.activation[j], 1e-8 * ms.activation[j]) << "t " << row[0] << " muscle " << j;
    }
  }
}

TEST(PostureDependentFlatness, ForwardMapAccelerationAndTorqueRateAgreeWithSimbody) {
  // qdd from the forward map equals Simbody's; q''' (which needs dR/dt F) equals the secant of
  // Simbody's accelerations over a tiny step.
  const auto model = posture_dependent_elbow();
  const fpl::FlatOutputMap flat(model);
  SimTK::State s = model->defaultState();
  model->setJointAngles(s, Eigen::VectorXd::Constant(1, 1.2));
  model->setJointSpeeds(s, Eigen::VectorXd::Constant(1, 2.0));
  const Eigen::Vector3d a(0.3, 0.2, 0.25);
  fp::equilibrate_tendons(*model, s, a);
  model->setExcitations(s, a);
  const fpl::FlatState y = flat.forward(fpl::muscle_state_of(*model, s));
  model->system().realize(s, SimTK::Stage::Acceleration);
  EXPECT_NEAR(y.q(0, 2), s.getUDot()[0], 1e-10 * (1 + std::abs(s.getUDot()[0])));
  fp::SimulationOptions o;
  const double dt = 1e-5;
  o.duration_s = dt;
  o.accuracy = 1e-12;
  o.report_interval_s = dt;
  const auto sim = fp::simulate(*model, s, o);
  const fpl::FlatState y_end = flat.forward(fpl::muscle_state_of(*model, sim.final_state));
  const double secant = (y_end.q(0, 2) - y.q(0, 2)) / dt, mid = 0.5 * (y.q(0, 3) + y_end.q(0, 3));
  EXPECT_NEAR(mid, secant, 1e-4 * (1 + std::abs(secant)));
  // Without the dR/dt F term q''' would differ by (dR/dt F) / M: make sure that is not small.
  const Eigen::MatrixXd R1 = flat.momentArms(Eigen::VectorXd::Constant(1, 1.2 + 1e-6));
  const Eigen::MatrixXd R0 = flat.momentArms(Eigen::VectorXd::Constant(1, 1.2));
  Eigen::VectorXd F(3);
  for (int j = 0; j < 3; ++j) F[j] = flatsos::muscles::tendon_force(model->muscle(j).getParameters(), model->tendonLengths(s)[j]);
  const double dR_F = ((R1 - R0) / 1e-6 * 2.0 * F)(0);  // qd = 2 rad/s
  const double inertia = model->massMatrix(Eigen::VectorXd::Constant(1, 1.2))(0, 0);
  EXPECT_GT(std::abs(dR_F) / inertia, 10.0 * 1e-4 * (1 + std::abs(secant)));
}

TEST(PostureDependentFlatness, Assumption1IsCheckedOverTheJointRangesNamingThePosture) {
  // A flexor (constant 0.03 m) and an "extensor" whose moment arm -0.02 + 2 c q changes sign at
  // q = 1.5 rad (85.94 deg), with E = their mean: C_tau = [1, -1] / (r1 - r2), so condition 3,
  // 1 - C_tau s_tau = -2 r2 / (r1 - r2) > 0, fails exactly where the extensor stops extending.
  const double c = 0.02 / 3.0;
  const std::string json = R"({"name": "sign_changing_extensor",
    "bodies": [{"name": "forearm", "mass_kg": 1.5, "mass_center_m": [0.17, 0, 0], "inertia_about_mass_center_kg_m2": 0.02}],
    "joints": [{"name": "elbow", "type": "pin", "parent": "ground", "child": "forearm", "location_in_parent_m": [0, 0, 0],
                "coordinate": "elbow_flexion", "range_rad": [0.0, 2.5]}],
    "muscles": [
      {"name": "flexor", "max_isometric_force_N": 800, "optimal_fiber_length_m": 0.12, "tendon_slack_length_m": 0.2,
       "length_at_zero_angles_m": 0.4, "moment_arms_m": {"elbow": 0.03}},
      {"name": "extensor", "max_isometric_force_N": 600, "optimal_fiber_length_m": 0.11, "tendon_slack_length_m": 0.15,
       "path": {"coordinates": ["elbow_flexion"], "order": 2, "coefficients": [0.25, 0.02, )" + std::to_string(-c) + R"(]}}],
    "flat_outputs": [{"name": "mean", "weights": {"flexor": 0.5, "extensor": 0.5}}]})";
  const auto model = std::make_shared<const fp::MusculoskeletalModel>(fp::parse_model_json(json, "test"));
  try {
    const fpl::FlatOutputMap flat(model);
    ADD_FAILURE() << "accepted an E that fails Assumption 1 beyond 86 deg";
  } catch (const fpl::FlatnessError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("condition 3"), std::string::npos) << what;
    EXPECT_NE(what.find("muscle 0"), std::string::npos) << what;
    const std::size_t at = what.find("elbow = ");
    ASSERT_NE(at, std::string::npos) << what;
    const double named_deg = std::stod(what.substr(at + 8));
    EXPECT_GE(named_deg, 85.94);  // the first grid posture past the sign change
    EXPECT_LE(named_deg, 85.94 + 143.24 / 19999 + 1e-6);
  }
  // The shipped elbow's E holds over its whole range, and the check along a path says where a
  // posture outside it fails.
  const fpl::FlatOutputMap elbow(posture_dependent_elbow());
  EXPECT_EQ(elbow.assumption1FailureAt(Eigen::VectorXd::Constant(1, deg(60))), "");
  Eigen::MatrixXd bad_E(2, 3);
  bad_E << 1.0, 0.0, 0.0, 1.0, 0.0, 0.0;  // two equal rows: C(q) singular in every posture
  try {
    const fpl::FlatOutputMap flat(posture_dependent_elbow(), bad_E);
    ADD_FAILURE() << "accepted an E with two equal rows";
  } catch (const fpl::FlatnessError& e) {
    EXPECT_NE(std::string(e.what()).find("elbow = 0.000000 deg"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("condition 1"), std::string::npos) << e.what();
  }
}

TEST(PostureDependentFlatness, WhatNeedsConstantMomentArmsSaysSo) {
  const fpl::FlatOutputMap flat(posture_dependent_elbow());
  EXPECT_THROW(flat.A(), std::logic_error);
  EXPECT_THROW(flat.CY(), std::logic_error);
  Eigen::MatrixXd gradient(3, 5);
  EXPECT_THROW(flat.pathLengthJetGradient(0, joint_jet(0.1, 5), gradient), std::logic_error);
  fpl::OpenLoopOptions o = fpl::open_loop_options(fpl::Preset::Paper);
  o.duration_s = 1.0;
  o.target_q_rad = Eigen::VectorXd::Constant(1, deg(90));
  o.reserves_N = Eigen::VectorXd::Constant(3, 10.0);
  o.free_path.enabled = true;
  SimTK::State s = flat.model().defaultState();
  fpl::set_minimum_effort_rest_state(flat, s, Eigen::VectorXd::Constant(1, deg(30)), o.reserves_N);
  try {
    fpl::plan_open_loop(flat, fpl::muscle_state_of(flat.model(), s), o);
    ADD_FAILURE() << "planned a free joint path";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("free_path needs constant moment arms"), std::string::npos) << e.what();
  }
}

TEST(PostureDependentFlatness, TorqueJetsThroughAJointsStopAreExact) {
  // The elbow's limit torque is only twice continuously differentiable at the ends of its
  // transition (2.5 and 2.6745 rad): differences in time across them would be off by the jump
  // in its third derivative. A motion that runs through the stop: the planner's jets (pointwise
  // and on a grid) against differences in time of tau(t) away from those ends, and against the
  // dual-number jets of the pin tree everywhere (close to the ends too).
  const fpl::FlatOutputMap flat(posture_dependent_elbow());
  ASSERT_TRUE(flat.model().hasJointLimits());
  const double c[4] = {2.2, 1.0, 0.5, -0.4};  // q(t) = sum c_k t^k: 2.5 rad at t = 0.27 s
  auto motion = [&](double t, int order) { return cubic_derivative(c, t, order); };
  auto jet_at = [&](double t) {
    fpl::Jet j(1, 5);
    for (int k = 0; k < 5; ++k) j(0, k) = motion(t, k);
    return j;
  };
  auto torque_at = [&](double t) {
    const fpl::Jet j = jet_at(t);
    return flat.torque(j.col(0), j.col(1), j.col(2))[0];
  };
  auto torque_rate_at = [&](double t) { return flat.torqueJet(jet_at(t)).tau(0, 1); };
  const double h = 0.05;
  fp::ModelWorkspace ws = flat.makeWorkspace();
  const std::vector<fpl::TorqueJet> grid = flat.torqueJetsOnGrid(ws, jet_at, 0.0, h, 17);
  double largest_limit_rate = 0.0;
  for (int i = 1; i < 17; ++i) {
    const double t = i * h;
    const fpl::TorqueJet jet = flat.torqueJet(jet_at(t));
    const Eigen::MatrixXd exact = flat.model().pinTree().torqueJet(jet_at(t));
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(jet.tau(0, k), exact(0, k), 1e-9 * (1.0 + std::abs(exact(0, k)))) << "t " << t << " order " << k;
      EXPECT_NEAR(grid[static_cast<std::size_t>(i)].tau(0, k), exact(0, k), 1e-6 * (1.0 + std::abs(exact(0, k))))
          << "grid t " << t << " order " << k;
    }
    Eigen::MatrixXd limit(1, 3);
    flat.model().pinTree().jointLimitTorqueJet(jet_at(t), limit);
    largest_limit_rate = std::max(largest_limit_rate, std::abs(limit(0, 2)));
    const double q = motion(t, 0);
    if (std::abs(q - 2.5) > 0.05 && std::abs(q - 2.6745) > 0.05) {
      EXPECT_MATCHES_FINITE_DIFFERENCE(jet.tau(0, 1), central_difference(torque_at, t, 1e-4)) << "t " << t;
      EXPECT_MATCHES_FINITE_DIFFERENCE(jet.tau(0, 2), central_difference(torque_rate_at, t, 1e-4)) << "t " << t;
    }
  }
  // The limit's own second rate is a large part of the jet there: the comparison means something.
  EXPECT_GT(largest_limit_rate, 1e3);
}

TEST(PostureDependentFlatness, TheForceJetMapWhereFlatChecksAssumption1AsTheDirectCheckDoes) {
  // The leg's flat outputs hold over its joint ranges; the elbow's too. At random postures (and
  // beyond the ranges, where they may not) the one-pass check agrees with assumption1FailureAt,
  // word for word, and where it holds gives forceJetMap's map; condition 3's margin read from
  // C_Y's row sums is 1 - C_tau s_tau.
  for (const char* file : {"elbow_posture_dependent.json", "sagittal_leg_r.json"}) {
    SCOPED_TRACE(file);
    const fpl::FlatOutputMap flat(fp::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) + "/models/" + file));
    const int n = flat.numJoints();
    std::mt19937 rng(29);
    std::uniform_real_distribution<double> share(-0.5, 1.5);
    const fp::ModelDescription& d = flat.model().description();
    int failing = 0;
    for (int trial = 0; trial < 40; ++trial) {
      fpl::Jet q = fpl::Jet::Zero(n, 3);
      for (int i = 0; i < n; ++i) {
        const auto& range = d.joints[static_cast<std::size_t>(i)].range_rad;
        q(i, 0) = range[0] + share(rng) * (range[1] - range[0]);
      }
      fpl::ForceJetMap map;
      const std::string failure = flat.forceJetMapWhereFlat(q, map);
      EXPECT_EQ(failure, flat.assumption1FailureAt(q.col(0))) << trial;
      if (!failure.empty()) {
        ++failing;
        continue;
      }
      const fpl::ForceJetMap direct = flat.forceJetMap(q);
      EXPECT_EQ(map.Ctau, direct.Ctau);
      EXPECT_EQ(map.CY, direct.CY);
      const Eigen::VectorXd s_tau = flat.model().momentArmMatrix(q.col(0)).rowwise().sum();
      const Eigen::VectorXd margin = Eigen::VectorXd::Ones(flat.numMuscles()) - map.Ctau * s_tau;
      EXPECT_LT((map.CY.rowwise().sum() - margin).cwiseAbs().maxCoeff(), 1e-9) << trial;
    }
    std::cout << "[ measure  ] " << file << ": " << failing << " of 40 postures outside Assumption 1\n";
  }
}
