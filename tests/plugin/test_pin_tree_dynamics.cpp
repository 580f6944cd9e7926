// The pin-tree inverse dynamics (recursive Newton-Euler, pin_tree_dynamics.hpp) against
// Simbody's own inverse dynamics of the same model (calcResidualForceIgnoringConstraints with
// the gravity body forces Simbody computes), on random trees: branching, joint axes in any
// direction, joint locations off the parent's origin, mass centres off the joint, products of
// inertia, gravity in any direction. Simbody is what simulates the plant, so this is the
// agreement the planner's plans rely on. The exact torque jets (dual numbers) against differences
// in time along the motion, and their gradients against finite differences, as are the
// derivatives of inverse dynamics with respect to (q, qd, qdd). Each again on trees where about
// half the joints are sliders (Simbody's Slider mobilizer), and a block sliding on a tilted rail
// against the hand computation F = m (qdd + g sin theta).

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <random>
#include <tuple>

#include <gtest/gtest.h>

#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace {

namespace fp = flatsos::plugin;

// Small errors as "1.23e-15" (what std::to_string would show as 0.000000).
std::string scientific(double x) {
  std::ostringstream out;
  out << std::scientific << std::setprecision(2) << x;
  return out.str();
}

Eigen::Vector3d random_vector(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return {u(rng), u(rng), u(rng)};
}

// A random tree of `joints` pins (each a slider with probability slider_fraction); body k hangs
// from a random earlier body (or ground) and carries one muscle so the description is valid
// (muscles do not enter inverse dynamics).
fp::ModelDescription random_tree(std::mt19937& rng, int joints, double slider_fraction = 0.0) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  fp::ModelDescription d;
  d.name = "random tree";
  d.gravity_m_per_s2 = random_vector(rng, 10.0);
  for (int k = 0; k < joints; ++k) {
    fp::BodyDescription b;
    b.name = "body" + std::to_string(k);
    b.mass_kg = 0.5 + 3.0 * u(rng);
    b.mass_center_m = random_vector(rng, 0.3);
    // A physical inertia about the mass centre: principal moments from second moments of mass
    // (so they satisfy the triangle inequality), rotated randomly.
    const Eigen::Matrix3d R = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
    const Eigen::Vector3d second(0.01 * u(rng), 0.01 * u(rng), 0.01 * u(rng));
    const Eigen::Vector3d moments(second[1] + second[2], second[0] + second[2], second[0] + second[1]);
    const Eigen::Matrix3d I = R * moments.asDiagonal() * R.transpose();
    b.principal_inertia_kg_m2 = I.diagonal();
    b.product_inertia_kg_m2 = Eigen::Vector3d(I(0, 1), I(0, 2), I(1, 2));
    d.bodies.push_back(b);
    fp::JointDescription j;
    j.name = "joint" + std::to_string(k);
    j.child = b.name;
    const int parent = std::uniform_int_distribution<int>(-1, k - 1)(rng);
    j.parent = parent < 0 ? "ground" : "body" + std::to_string(parent);
    j.location_in_parent_m = random_vector(rng, 0.4);
    j.axis = random_vector(rng, 1.0).normalized();
    if (slider_fraction > 0.0 && u(rng) < slider_fraction) j.type = fp::JointType::Slider;
    d.joints.push_back(j);
  }
  const auto is_slider = [](const fp::JointDescription& j) { return j.isSlider(); };
  if (slider_fraction > 0.0 && std::none_of(d.joints.begin(), d.joints.end(), is_slider))
    d.joints.back().type = fp::JointType::Slider;  // every tree asked for sliders has one
  fp::MuscleDescription m;
  m.parameters.name = "muscle";
  m.parameters.max_isometric_force_N = 100.0;
  m.parameters.optimal_fiber_length_m = 0.1;
  m.parameters.tendon_slack_length_m = 0.1;
  m.length_at_zero_angles_m = 0.25;
  m.moment_arms_m = Eigen::VectorXd::Constant(joints, 0.01);
  d.muscles.push_back(m);
  return d;
}

// Simbody's inverse dynamics of the model at (q, qd, qdd): gravity only.
Eigen::VectorXd simbody_inverse_dynamics(const fp::MusculoskeletalModel& model, const Eigen::VectorXd& q,
                                         const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
  SimTK::State s = model.defaultState();
  model.setJointAngles(s, q);
  model.setJointSpeeds(s, qd);
  model.system().realize(s, SimTK::Stage::Dynamics);
  // Gravity is the model's only body force (muscles and external torques act as mobility forces).
  const SimTK::Vector_<SimTK::SpatialVec>& body_forces = model.system().getRigidBodyForces(s, SimTK::Stage::Dynamics);
  SimTK::Vector udot(s.getNU(), 0.0), residual;
  for (int i = 0; i < model.numJoints(); ++i) udot[model.joint(i).getFirstUIndex(s)] = qdd[i];
  model.matter().calcResidualForceIgnoringConstraints(s, SimTK::Vector(), body_forces, udot, residual);
  Eigen::VectorXd tau(model.numJoints());
  for (int i = 0; i < model.numJoints(); ++i) tau[i] = residual[model.joint(i).getFirstUIndex(s)];
  return tau;
}

double worst_disagreement_with_simbody(unsigned seed, double slider_fraction) {
  std::mt19937 rng(seed);
  std::srand(7);  // Eigen's UnitRandom uses std::rand
  double worst = 0.0;
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 1 + trial % 6;
    const fp::MusculoskeletalModel model(random_tree(rng, n, slider_fraction));
    fp::ModelWorkspace ws = model.makeWorkspace();
    for (int k = 0; k < 5; ++k) {
      const Eigen::VectorXd q = Eigen::VectorXd::Random(n) * 3.0, qd = Eigen::VectorXd::Random(n) * 4.0,
                            qdd = Eigen::VectorXd::Random(n) * 20.0;
      const Eigen::VectorXd expected = simbody_inverse_dynamics(model, q, qd, qdd);
      const Eigen::VectorXd tau = model.inverseDynamics(ws, q, qd, qdd);
      const double error = (tau - expected).cwiseAbs().maxCoeff() / (1.0 + expected.cwiseAbs().maxCoeff());
      worst = std::max(worst, error);
      EXPECT_LT(error, 1e-12) << "trial " << trial << ", " << n << " joints: " << tau.transpose() << " vs Simbody "
                              << expected.transpose();
    }
  }
  return worst;
}

TEST(PinTreeDynamics, AgreesWithSimbodyOnRandomTrees) {
  RecordProperty("worst_relative_error", scientific(worst_disagreement_with_simbody(20261123, 0.0)));
}

TEST(PinTreeDynamics, AgreesWithSimbodyOnRandomTreesWithSliders) {
  RecordProperty("worst_relative_error", scientific(worst_disagreement_with_simbody(20261125, 0.5)));
}

// Property: without gravity, at rest and with qdd = 0 nothing is needed; the torque is linear
// in qdd (the mass matrix) and the velocity terms are quadratic in qd.
void check_each_term_vanishes_alone(double slider_fraction) {
  std::mt19937 rng(3);
  fp::ModelDescription d = random_tree(rng, 4, slider_fraction);
  d.gravity_m_per_s2.setZero();
  const fp::MusculoskeletalModel model(d);
  fp::ModelWorkspace ws = model.makeWorkspace();
  const Eigen::VectorXd q = Eigen::VectorXd::Random(4), qd = Eigen::VectorXd::Random(4), qdd = Eigen::VectorXd::Random(4);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(4);
  EXPECT_LT(model.inverseDynamics(ws, q, zero, zero).cwiseAbs().maxCoeff(), 1e-14);
  const Eigen::VectorXd velocity = model.inverseDynamics(ws, q, qd, zero);
  EXPECT_LT((model.inverseDynamics(ws, q, 2.0 * qd, zero) - 4.0 * velocity).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::VectorXd M_qdd = model.inverseDynamics(ws, q, zero, qdd);
  EXPECT_LT((M_qdd - model.massMatrix(ws, q) * qdd).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT(velocity.cwiseAbs().maxCoeff(), 1e-3);  // the terms are there at all
}

TEST(PinTreeDynamics, EachTermVanishesAlone) { check_each_term_vanishes_alone(0.0); }
TEST(PinTreeDynamics, EachTermVanishesAloneWithSliders) { check_each_term_vanishes_alone(0.5); }

TEST(PinTreeDynamics, RejectsWrongSizesAndForeignWorkspaces) {
  std::mt19937 rng(5);
  const fp::MusculoskeletalModel a(random_tree(rng, 2)), b(random_tree(rng, 2));
  fp::ModelWorkspace ws = a.makeWorkspace();
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(2);
  Eigen::VectorXd tau(2), short_tau(1);
  EXPECT_THROW(b.inverseDynamics(ws, v, v, v, tau), std::invalid_argument);
  EXPECT_THROW(a.inverseDynamics(ws, v, v, v, short_tau), std::invalid_argument);
  EXPECT_THROW(a.inverseDynamics(ws, Eigen::VectorXd::Zero(3), v, v, tau), std::invalid_argument);
  EXPECT_THROW(a.inverseDynamics(ws, v, Eigen::VectorXd::Constant(2, std::nan("")), v, tau), std::invalid_argument);
}

}  // namespace

namespace {
TEST(PinTreeDynamics, AnUnphysicalInertiaIsRejectedNamingTheBodyNotBySimbody) {
  // Built in code (not from a file): the description's validation names the field before
  // Simbody's Inertia throws its own message.
  std::mt19937 rng(9);
  fp::ModelDescription d = random_tree(rng, 2);
  d.bodies[1].principal_inertia_kg_m2 = Eigen::Vector3d(0.01, 0.01, 0.01);
  d.bodies[1].product_inertia_kg_m2 = Eigen::Vector3d(0.0, 0.0, 0.008);  // |2 Iyz| > Ixx
  try {
    const fp::MusculoskeletalModel model(d);
    ADD_FAILURE() << "an unphysical inertia was accepted";
  } catch (const fp::ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find("bodies[1].product_inertia_kg_m2"), std::string::npos) << e.what();
  }
  d.bodies[1].product_inertia_kg_m2.setZero();
  d.bodies[1].principal_inertia_kg_m2 = Eigen::Vector3d(0.01, 0.01, 0.05);  // triangle inequality
  EXPECT_THROW(fp::MusculoskeletalModel{d}, fp::ModelFileError);
}
}  // namespace

namespace {

// The joint motion q(t) = sum_l q^(l) t^l / l! through a jet (N x 5) at t = 0.
struct TaylorMotion {
  Eigen::MatrixXd jet;
  Eigen::VectorXd derivative(int order, double t) const {
    Eigen::VectorXd out = Eigen::VectorXd::Zero(jet.rows());
    double factorial = 1.0;
    for (int l = order; l < jet.cols(); ++l) {
      out += jet.col(l) * std::pow(t, l - order) / factorial;
      factorial *= (l - order + 1);
    }
    return out;
  }
};

// Independent of the dual numbers: differences in time of the double-precision inverse
// dynamics along the Taylor curve of the jet (fourth order, step 1e-3 s: error ~1e-10 relative).
double check_torque_jet_against_time_differences(double slider_fraction) {
  std::mt19937 rng(11);
  std::srand(13);
  double worst = 0.0;
  for (int trial = 0; trial < 12; ++trial) {
    const int n = 1 + trial % 5;
    const fp::MusculoskeletalModel model(random_tree(rng, n, slider_fraction));
    fp::ModelWorkspace ws = model.makeWorkspace();
    TaylorMotion motion{Eigen::MatrixXd::Random(n, 5)};
    motion.jet.col(1) *= 3.0;
    motion.jet.col(2) *= 10.0;
    motion.jet.col(3) *= 30.0;
    motion.jet.col(4) *= 100.0;
    auto tau_at = [&](double t) {
      return model.inverseDynamics(ws, motion.derivative(0, t), motion.derivative(1, t), motion.derivative(2, t));
    };
    const double h = 1e-3;
    const Eigen::VectorXd t_m2 = tau_at(-2 * h), t_m1 = tau_at(-h), t_0 = tau_at(0.0), t_p1 = tau_at(h), t_p2 = tau_at(2 * h);
    const Eigen::VectorXd first = (t_m2 - 8.0 * t_m1 + 8.0 * t_p1 - t_p2) / (12.0 * h);
    const Eigen::VectorXd second = (-t_m2 + 16.0 * t_m1 - 30.0 * t_0 + 16.0 * t_p1 - t_p2) / (12.0 * h * h);
    const Eigen::MatrixXd jet = model.pinTree().torqueJet(motion.jet);
    const double scale = 1.0 + jet.cwiseAbs().maxCoeff();
    EXPECT_LT((jet.col(0) - t_0).cwiseAbs().maxCoeff(), 1e-12 * scale);
    const double e1 = (jet.col(1) - first).cwiseAbs().maxCoeff() / scale, e2 = (jet.col(2) - second).cwiseAbs().maxCoeff() / scale;
    EXPECT_LT(e1, 1e-7) << "trial " << trial;
    EXPECT_LT(e2, 1e-5) << "trial " << trial;
    worst = std::max({worst, e1, e2});
  }
  return worst;
}

TEST(PinTreeDynamics, TorqueJetIsTheTimeDerivativeOfInverseDynamicsAlongTheMotion) {
  RecordProperty("worst_relative_error", scientific(check_torque_jet_against_time_differences(0.0)));
}
TEST(PinTreeDynamics, TorqueJetIsTheTimeDerivativeOfInverseDynamicsWithSliders) {
  RecordProperty("worst_relative_error", scientific(check_torque_jet_against_time_differences(0.5)));
}

void check_torque_jet_gradient(double slider_fraction) {
  std::mt19937 rng(17);
  std::srand(19);
  for (int trial = 0; trial < 6; ++trial) {
    const int n = 1 + trial % 4;
    const fp::MusculoskeletalModel model(random_tree(rng, n, slider_fraction));
    Eigen::MatrixXd q_jet = Eigen::MatrixXd::Random(n, 5);
    q_jet.col(2) *= 10.0;
    Eigen::MatrixXd gradient;
    const Eigen::MatrixXd jet = model.pinTree().torqueJet(q_jet, gradient);
    EXPECT_LT((jet - model.pinTree().torqueJet(q_jet)).cwiseAbs().maxCoeff(), 1e-13 * (1.0 + jet.cwiseAbs().maxCoeff()));
    ASSERT_EQ(gradient.rows(), 3 * n);
    ASSERT_EQ(gradient.cols(), 5 * n);
    for (int r = 0; r < n; ++r)
      for (int l = 0; l < 5; ++l) {
        const double h = 1e-6 * (1.0 + std::abs(q_jet(r, l)));
        Eigen::MatrixXd plus = q_jet, minus = q_jet;
        plus(r, l) += h;
        minus(r, l) -= h;
        const Eigen::MatrixXd difference = (model.pinTree().torqueJet(plus) - model.pinTree().torqueJet(minus)) / (2 * h);
        for (int i = 0; i < n; ++i)
          for (int k = 0; k < 3; ++k) {
            const double fd = difference(i, k), exact = gradient(3 * i + k, 5 * r + l);
            EXPECT_NEAR(exact, fd, 1e-7 * (1.0 + std::abs(fd) + jet.cwiseAbs().maxCoeff()))
                << "d tau" << i << "^(" << k << ") / d q" << r << "^(" << l << ")";
          }
      }
    // Structure: tau does not depend on q''' or q''''; dtau/dt not on q''''.
    for (int i = 0; i < n; ++i)
      for (int r = 0; r < n; ++r) {
        EXPECT_EQ(gradient(3 * i, 5 * r + 3), 0.0);
        EXPECT_EQ(gradient(3 * i, 5 * r + 4), 0.0);
        EXPECT_EQ(gradient(3 * i + 1, 5 * r + 4), 0.0);
      }
  }
}

TEST(PinTreeDynamics, TorqueJetGradientMatchesFiniteDifferences) { check_torque_jet_gradient(0.0); }
TEST(PinTreeDynamics, TorqueJetGradientMatchesFiniteDifferencesWithSliders) { check_torque_jet_gradient(0.5); }

// Central differences of the exact (dual-number) gradient, entry by entry, including the pairs
// the Hessian skips as structurally zero: the differences must find them zero too.
void check_torque_jet_hessian(double slider_fraction) {
  std::mt19937 rng(41);
  std::srand(43);
  for (int trial = 0; trial < 6; ++trial) {
    const int n = 1 + trial % 4;
    const fp::MusculoskeletalModel model(random_tree(rng, n, slider_fraction));
    const fp::PinTreeDynamics& tree = model.pinTree();
    Eigen::MatrixXd q_jet = Eigen::MatrixXd::Random(n, 5);
    q_jet.col(2) *= 10.0;
    const Eigen::MatrixXd w = Eigen::MatrixXd::Random(n, 3);
    auto weighted_gradient = [&](const Eigen::MatrixXd& jet) {
      Eigen::MatrixXd gradient;
      tree.torqueJet(jet, gradient);
      Eigen::VectorXd g = Eigen::VectorXd::Zero(5 * n);
      for (int i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) g += w(i, k) * gradient.row(3 * i + k).transpose();
      return g;
    };
    const Eigen::MatrixXd H = tree.torqueJetHessian(q_jet, w);
    ASSERT_EQ(H.rows(), 5 * n);
    ASSERT_EQ(H.cols(), 5 * n);
    EXPECT_TRUE(H.isApprox(H.transpose(), 0.0));
    const double scale = 1.0 + weighted_gradient(q_jet).cwiseAbs().maxCoeff();
    double largest = 0.0;
    for (int c = 0; c < 5 * n; ++c) {
      const double h = 1e-6 * (1.0 + std::abs(q_jet(c / 5, c % 5)));
      Eigen::MatrixXd plus = q_jet, minus = q_jet;
      plus(c / 5, c % 5) += h;
      minus(c / 5, c % 5) -= h;
      const Eigen::VectorXd fd = (weighted_gradient(plus) - weighted_gradient(minus)) / (2 * h);
      for (int b = 0; b < 5 * n; ++b) {
        EXPECT_NEAR(H(b, c), fd[b], 1e-6 * scale) << "d2 / d q" << b / 5 << "^(" << b % 5 << ") d q" << c / 5 << "^("
                                                   << c % 5 << "), trial " << trial;
        largest = std::max(largest, std::abs(H(b, c)));
      }
    }
    // A Hessian that is really there, where a pin turns something: a tree of sliders alone has
    // a constant mass matrix and no velocity terms, so its torques are linear (Hessian 0).
    const auto is_pin = [](const fp::JointDescription& j) { return !j.isSlider(); };
    const auto& joints = model.description().joints;
    if (std::any_of(joints.begin(), joints.end(), is_pin)) EXPECT_GT(largest, 1e-3 * scale);
    else EXPECT_EQ(largest, 0.0);
  }
}

TEST(PinTreeDynamics, TorqueJetHessianIsTheDerivativeOfTheWeightedExactGradient) { check_torque_jet_hessian(0.0); }
TEST(PinTreeDynamics, TorqueJetHessianWithSliders) { check_torque_jet_hessian(0.5); }

TEST(PinTreeDynamics, TorqueJetHessianRejectsWrongShapes) {
  std::mt19937 rng2(47);
  const fp::MusculoskeletalModel model(random_tree(rng2, 2));
  EXPECT_THROW(model.pinTree().torqueJetHessian(Eigen::MatrixXd::Zero(2, 5), Eigen::MatrixXd::Zero(2, 2)), std::invalid_argument);
  EXPECT_THROW(model.pinTree().torqueJetHessian(Eigen::MatrixXd::Zero(2, 4), Eigen::MatrixXd::Zero(2, 3)), std::invalid_argument);
}

void check_inverse_dynamics_jacobian_and_hessian(double slider_fraction) {
  std::mt19937 rng(29);
  std::srand(31);
  for (int trial = 0; trial < 6; ++trial) {
    const int n = 1 + trial % 4;
    const fp::MusculoskeletalModel model(random_tree(rng, n, slider_fraction));
    const fp::PinTreeDynamics& tree = model.pinTree();
    const Eigen::VectorXd x = (Eigen::VectorXd(3 * n) << Eigen::VectorXd::Random(n), 3.0 * Eigen::VectorXd::Random(n),
                               10.0 * Eigen::VectorXd::Random(n)).finished();
    const Eigen::VectorXd w = Eigen::VectorXd::Random(n);
    auto tau_at = [&](const Eigen::VectorXd& y) {
      return model.inverseDynamics(y.head(n), y.segment(n, n), y.tail(n));
    };
    auto jacobian_at = [&](const Eigen::VectorXd& y) {
      Eigen::MatrixXd J;
      const Eigen::VectorXd tau = tree.inverseDynamicsJacobian(y.head(n), y.segment(n, n), y.tail(n), J);
      EXPECT_LT((tau - tau_at(y)).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + tau.cwiseAbs().maxCoeff()));
      return J;
    };
    const Eigen::MatrixXd J = jacobian_at(x);
    const Eigen::MatrixXd H = tree.inverseDynamicsHessian(x.head(n), x.segment(n, n), x.tail(n), w);
    ASSERT_EQ(J.rows(), n);
    ASSERT_EQ(J.cols(), 3 * n);
    ASSERT_EQ(H.rows(), 3 * n);
    ASSERT_EQ(H.cols(), 3 * n);
    const double scale = 1.0 + tau_at(x).cwiseAbs().maxCoeff();
    for (int c = 0; c < 3 * n; ++c) {
      const double h = 1e-6 * (1.0 + std::abs(x[c]));
      Eigen::VectorXd plus = x, minus = x;
      plus[c] += h;
      minus[c] -= h;
      // First derivatives from the torques, second ones from the exact Jacobian's differences.
      const Eigen::VectorXd d_tau = (tau_at(plus) - tau_at(minus)) / (2 * h);
      const Eigen::VectorXd d_wJ = (w.transpose() * (jacobian_at(plus) - jacobian_at(minus))).transpose() / (2 * h);
      for (int i = 0; i < n; ++i)
        EXPECT_NEAR(J(i, c), d_tau[i], 1e-7 * scale) << "d tau" << i << " / d x" << c << ", trial " << trial;
      for (int b = 0; b < 3 * n; ++b)
        EXPECT_NEAR(H(b, c), d_wJ[b], 1e-6 * scale) << "d2 (w tau) / d x" << b << " d x" << c << ", trial " << trial;
    }
    EXPECT_TRUE(H.isApprox(H.transpose(), 0.0));
  }
}

TEST(PinTreeDynamics, InverseDynamicsJacobianAndHessianMatchFiniteDifferences) {
  check_inverse_dynamics_jacobian_and_hessian(0.0);
}
TEST(PinTreeDynamics, InverseDynamicsJacobianAndHessianWithSliders) { check_inverse_dynamics_jacobian_and_hessian(0.5); }

TEST(PinTreeDynamics, InverseDynamicsDerivativesRejectWrongSizes) {
  std::mt19937 rng(37);
  const fp::MusculoskeletalModel model(random_tree(rng, 2));
  Eigen::MatrixXd J;
  const Eigen::VectorXd two = Eigen::VectorXd::Zero(2), three = Eigen::VectorXd::Zero(3);
  EXPECT_THROW(model.pinTree().inverseDynamicsJacobian(two, three, two, J), std::invalid_argument);
  EXPECT_THROW(model.pinTree().inverseDynamicsHessian(two, two, two, three), std::invalid_argument);
}

TEST(PinTreeDynamics, TorqueJetRejectsAJetOfTheWrongShape) {
  std::mt19937 rng(23);
  const fp::MusculoskeletalModel model(random_tree(rng, 2));
  EXPECT_THROW(model.pinTree().torqueJet(Eigen::MatrixXd::Zero(2, 4)), std::invalid_argument);
  EXPECT_THROW(model.pinTree().torqueJet(Eigen::MatrixXd::Zero(3, 5)), std::invalid_argument);
}

}  // namespace

namespace {

fp::BodyDescription box(const std::string& name, double mass_kg, const Eigen::Vector3d& mass_center_m,
                        const Eigen::Vector3d& inertia_kg_m2) {
  fp::BodyDescription b;
  b.name = name;
  b.mass_kg = mass_kg;
  b.mass_center_m = mass_center_m;
  b.principal_inertia_kg_m2 = inertia_kg_m2;
  return b;
}

fp::JointDescription joint(const std::string& name, fp::JointType type, const std::string& parent, const std::string& child,
                           const Eigen::Vector3d& location_m, const Eigen::Vector3d& axis) {
  fp::JointDescription j;
  j.name = name;
  j.type = type;
  j.parent = parent;
  j.child = child;
  j.location_in_parent_m = location_m;
  j.axis = axis.normalized();
  return j;
}

// One muscle with a moment arm on every joint, so that the description is valid.
fp::MuscleDescription any_muscle(int joints) {
  fp::MuscleDescription m;
  m.parameters.name = "muscle";
  m.parameters.max_isometric_force_N = 100.0;
  m.parameters.optimal_fiber_length_m = 0.1;
  m.parameters.tendon_slack_length_m = 0.1;
  m.length_at_zero_angles_m = 0.25;
  m.moment_arms_m = Eigen::VectorXd::Constant(joints, 0.01);
  return m;
}

}  // namespace

// A block of mass m on a rail tilted by theta from the horizontal, gravity straight down: the
// force along the rail that gives it acceleration qdd is F = m (qdd + g sin theta), whatever its
// position, speed and inertia (it does not turn).
TEST(PinTreeDynamics, ABlockOnATiltedSliderNeedsMassTimesAccelerationPlusGravityAlongTheRail) {
  const double m = 3.5, g = 9.81;
  for (const double theta : {0.0, 0.3, -0.7, 1.2}) {
    fp::ModelDescription d;
    d.gravity_m_per_s2 = Eigen::Vector3d(0.0, -g, 0.0);
    d.bodies.push_back(box("block", m, Eigen::Vector3d(0.05, -0.02, 0.01), Eigen::Vector3d(0.02, 0.03, 0.04)));
    d.joints.push_back(joint("rail", fp::JointType::Slider, "ground", "block", Eigen::Vector3d(0.1, 0.2, 0.0),
                             Eigen::Vector3d(std::cos(theta), std::sin(theta), 0.0)));
    d.muscles.push_back(any_muscle(1));
    const fp::MusculoskeletalModel model(d);
    fp::ModelWorkspace ws = model.makeWorkspace();
    for (const auto& [q, qd, qdd] : {std::tuple{0.0, 0.0, 0.0}, std::tuple{0.4, -1.5, 2.0}, std::tuple{-1.0, 3.0, -7.5}}) {
      const Eigen::VectorXd Q = Eigen::VectorXd::Constant(1, q), QD = Eigen::VectorXd::Constant(1, qd),
                            QDD = Eigen::VectorXd::Constant(1, qdd);
      const double by_hand_N = m * (qdd + g * std::sin(theta));
      EXPECT_NEAR(model.inverseDynamics(ws, Q, QD, QDD)[0], by_hand_N, 1e-12 * (1.0 + std::abs(by_hand_N))) << theta;
      EXPECT_NEAR(simbody_inverse_dynamics(model, Q, QD, QDD)[0], by_hand_N, 1e-12 * (1.0 + std::abs(by_hand_N))) << theta;
    }
    EXPECT_NEAR(model.massMatrix(Eigen::VectorXd::Constant(1, 0.3))(0, 0), m, 1e-12);
    // The block's frame slides along the rail without turning.
    SimTK::State s = model.defaultState();
    model.setJointAngles(s, Eigen::VectorXd::Constant(1, 0.25));
    model.system().realize(s, SimTK::Stage::Position);
    const SimTK::Transform& X = model.joint(0).getBodyTransform(s);
    const SimTK::Vec3 expected(0.1 + 0.25 * std::cos(theta), 0.2 + 0.25 * std::sin(theta), 0.0);
    EXPECT_LT((X.p() - expected).norm(), 1e-14);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(X.R().asMat33()[r][c], r == c ? 1.0 : 0.0, 1e-15);
  }
}

// A chain pin - slider - pin in 3-D: the slider's axis turns with the first pin and carries the
// last pin, so the Coriolis term 2 w x (axis qd) and the moments of a sliding body about the
// turning one all appear; Simbody's inverse dynamics of the same chain is the reference.
TEST(PinTreeDynamics, APinSliderPinChainIn3DAgreesWithSimbody) {
  fp::ModelDescription d;
  d.gravity_m_per_s2 = Eigen::Vector3d(0.5, -9.81, 1.2);
  d.bodies.push_back(box("arm", 2.0, Eigen::Vector3d(0.2, 0.05, -0.03), Eigen::Vector3d(0.01, 0.03, 0.035)));
  d.bodies.push_back(box("sleeve", 1.2, Eigen::Vector3d(0.0, 0.04, 0.02), Eigen::Vector3d(0.004, 0.005, 0.006)));
  d.bodies.push_back(box("hand", 0.6, Eigen::Vector3d(0.08, -0.01, 0.02), Eigen::Vector3d(0.002, 0.002, 0.003)));
  d.joints.push_back(joint("shoulder", fp::JointType::Pin, "ground", "arm", Eigen::Vector3d(0.0, 0.1, 0.0),
                           Eigen::Vector3d(0.2, 0.3, 1.0)));
  d.joints.push_back(joint("telescope", fp::JointType::Slider, "arm", "sleeve", Eigen::Vector3d(0.3, 0.02, -0.01),
                           Eigen::Vector3d(1.0, 0.4, -0.2)));
  d.joints.push_back(joint("wrist", fp::JointType::Pin, "sleeve", "hand", Eigen::Vector3d(0.05, 0.0, 0.03),
                           Eigen::Vector3d(-0.3, 1.0, 0.5)));
  d.muscles.push_back(any_muscle(3));
  const fp::MusculoskeletalModel model(d);
  fp::ModelWorkspace ws = model.makeWorkspace();
  std::mt19937 rng(53);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0.0;
  for (int k = 0; k < 20; ++k) {
    const Eigen::Vector3d q(2.0 * u(rng), 0.3 * u(rng), 2.0 * u(rng)), qd(4.0 * u(rng), 2.0 * u(rng), 4.0 * u(rng)),
        qdd(20.0 * u(rng), 10.0 * u(rng), 20.0 * u(rng));
    const Eigen::VectorXd expected = simbody_inverse_dynamics(model, q, qd, qdd);
    const Eigen::VectorXd tau = model.inverseDynamics(ws, q, qd, qdd);
    const double error = (tau - expected).cwiseAbs().maxCoeff() / (1.0 + expected.cwiseAbs().maxCoeff());
    worst = std::max(worst, error);
    EXPECT_LT(error, 1e-12) << tau.transpose() << " vs Simbody " << expected.transpose();
  }
  // Without the slider's speed its Coriolis term is gone: the result must change with it.
  const Eigen::Vector3d q(0.3, 0.1, -0.4), qdd = Eigen::Vector3d::Zero();
  const Eigen::VectorXd sliding = model.inverseDynamics(ws, q, Eigen::Vector3d(2.0, 1.5, 0.0), qdd);
  const Eigen::VectorXd still = model.inverseDynamics(ws, q, Eigen::Vector3d(2.0, 0.0, 0.0), qdd);
  EXPECT_GT(std::abs(sliding[0] - still[0]), 1e-3);
  RecordProperty("worst_relative_error", scientific(worst));
}
