// Static optimization along a measured motion (static_optimization.hpp): OpenSim's arm26
// tutorial motion against OpenSim's own static optimization of it, the torque balance at every
// frame, the rigid-tendon rule written out again, and what happens when the muscles cannot.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/planner/static_optimization.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"
#include "flatsos/plugin/io/sto_file.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;

namespace {

const std::string kArm26 = std::string(FLATSOS_SOURCE_DIR) + "/models/opensim/arm26/";

// arm26 as downloaded (imported once per kind: the path fit takes seconds), with its geometry
// paths, which static optimization uses as OpenSim does.
std::shared_ptr<const fp::MusculoskeletalModel> arm26(bool opensim_2_muscles) {
  static std::shared_ptr<const fp::MusculoskeletalModel> models[2];
  auto& model = models[opensim_2_muscles ? 1 : 0];
  if (!model)
    model = std::make_shared<const fp::MusculoskeletalModel>(fp::import_opensim_file(kArm26 + "arm26.osim", true, opensim_2_muscles).model);
  return model;
}

const fp::ProcessedCoordinates& tutorial_motion() {
  static const fp::ProcessedCoordinates motion = fp::process_coordinates_like_opensim(
      fp::read_sto(kArm26 + "inverse_kinematics/arm26_InverseKinematics.mot"), 6.0,
      std::vector<std::string>{"r_shoulder_elev", "r_elbow_flex"});
  return motion;
}

}  // namespace

TEST(StaticOptimization, Arm26AgreesWithOpenSimsStaticOptimization) {
  // The tutorial's setup: exponent 2, muscle physiology, coordinates filtered at 6 Hz, OpenSim
  // 2.x's Thelen muscles (the results were made by OpenSim 2.x) and its force per activation.
  const auto model = arm26(true);
  const fpl::StaticOptimizationResult r = fpl::static_optimization(*model, tutorial_motion());
  ASSERT_TRUE(r.success()) << r.failures.front();
  EXPECT_EQ(r.strength_rule, fpl::MuscleStrengthRule::OpenSim2);
  const fp::StoTable activation = fp::read_sto(kArm26 + "static_optimization/arm26_StaticOptimization_activation.sto");
  const fp::StoTable force = fp::read_sto(kArm26 + "static_optimization/arm26_StaticOptimization_force.sto");
  ASSERT_EQ(activation.rows.size(), r.time_s.size());
  double worst_activation = 0.0, worst_force_N = 0.0, worst_strength = 0.0, worst_effort = 0.0;
  for (std::size_t f = 0; f < r.time_s.size(); ++f) {
    ASSERT_NEAR(activation.rows[f][0], r.time_s[f], 1e-6);
    double opensim_effort = 0.0;
    for (int j = 0; j < model->numMuscles(); ++j) {
      const std::string& name = model->description().muscles[static_cast<std::size_t>(j)].parameters.name;
      const double a = activation.rows[f][static_cast<std::size_t>(activation.columnIndex(name))];
      const double F = force.rows[f][static_cast<std::size_t>(force.columnIndex(name))];
      const auto fi = static_cast<Eigen::Index>(f);
      worst_activation = std::max(worst_activation, std::abs(r.activation(fi, j) - a));
      worst_force_N = std::max(worst_force_N, std::abs(r.tendon_force_N(fi, j) - F));
      // The force per unit activation, where OpenSim's activation is large enough to read it.
      if (a > 0.01 && r.activation(fi, j) > 0.01)
        worst_strength = std::max(worst_strength, std::abs(r.tendon_force_N(fi, j) / r.activation(fi, j) / (F / a) - 1.0));
      opensim_effort += a * a;
    }
    worst_effort = std::max(worst_effort, std::abs(r.effort[static_cast<Eigen::Index>(f)] - opensim_effort));
  }
  std::printf("arm26 static optimization vs OpenSim's: activation %.3g, force %.3g N, force per activation %.3g "
              "relative, effort %.3g; %zu frames in %.3g ms\n",
              worst_activation, worst_force_N, worst_strength, worst_effort, r.time_s.size(), 1e3 * r.wall_seconds);
  EXPECT_LT(worst_activation, 0.02);  // the task's bound; measured 0.0053 (OpenSim's optimizer stops at 1e-4)
  EXPECT_LT(worst_strength, 1e-4);    // measured 2e-5: the same force per activation as OpenSim's
  EXPECT_LT(worst_effort, 1e-3);      // measured 1.5e-4 of efforts up to 0.3

  // Every frame balances the inverse-dynamics torques with the geometry's moment arms, inside
  // the bounds.
  fp::ModelWorkspace ws = model->makeWorkspace();
  const auto& motion = tutorial_motion();
  double worst_torque_N_m = 0.0;
  for (std::size_t f = 0; f < r.time_s.size(); ++f) {
    Eigen::VectorXd q(2), qd(2), qdd(2), tau(2);
    for (int i = 0; i < 2; ++i) {
      const auto& s = motion.spline(model->description().joints[static_cast<std::size_t>(i)].coordinateName());
      q[i] = s.value(r.time_s[f]), qd[i] = s.firstDerivative(r.time_s[f]), qdd[i] = s.secondDerivative(r.time_s[f]);
    }
    model->inverseDynamics(ws, q, qd, qdd, tau);
    Eigen::MatrixXd arms;
    fpl::muscle_strength_N(*model, r.strength_rule, q, qd, arms);
    const auto fi = static_cast<Eigen::Index>(f);
    worst_torque_N_m = std::max(worst_torque_N_m, (arms * r.tendon_force_N.row(fi).transpose() - tau).cwiseAbs().maxCoeff());
    EXPECT_TRUE(((r.activation.row(fi).array() >= 0.0) && (r.activation.row(fi).array() <= 1.0)).all());
  }
  EXPECT_LT(worst_torque_N_m, 1e-8);
}

TEST(StaticOptimization, TheRigidTendonRuleIsTheFibresActiveForceAlongTheTendon) {
  // Written out again on the paper's arm (polynomial paths): tendon at slack, the fibre from its
  // constant thickness, the model's own curves, dL/dt = -r^T qd.
  const auto model = fp::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) + "/models/arm_richter_warner.json");
  const Eigen::Vector2d q(0.3, 1.2), qd(-0.5, 2.0);
  Eigen::MatrixXd R;
  const Eigen::VectorXd G = fpl::muscle_strength_N(*model, fpl::MuscleStrengthRule::RigidTendon, q, qd, R);
  EXPECT_LT((R - model->momentArmMatrix(q)).cwiseAbs().maxCoeff(), 1e-15);
  for (int j = 0; j < model->numMuscles(); ++j) {
    const auto& p = model->description().muscles[static_cast<std::size_t>(j)].parameters;
    const double x = model->musculotendonLength(j, q) - p.tendon_slack_length_m;
    const double h = p.optimal_fiber_length_m * std::sin(p.pennation_angle_at_optimal_rad);
    const double fiber = std::sqrt(x * x + h * h), cos_phi = x / fiber;
    const double lengthening = -R.col(j).dot(qd);
    const double expected = p.max_isometric_force_N * p.model->activeForceLength(p, fiber).value *
                            p.model->forceVelocity(p, -cos_phi * lengthening).value * cos_phi;
    EXPECT_NEAR(G[j], expected, 1e-9 * p.max_isometric_force_N) << p.name;
    EXPECT_GT(G[j], 0.0) << p.name;
  }
}

namespace {
// The paper's arm from [20, 20] to [20 + 60 s, 20 + 60 s] deg over 1 s (s = smoothstep), the
// elbow's amplitude times `elbow_scale`, sampled at 100 Hz, in degrees as a .mot.
fp::StoTable arm_motion(double elbow_scale, const std::string& elbow_column = "elbow") {
  fp::StoTable t;
  t.in_degrees = true;
  t.columns = {"time", "shoulder", elbow_column};
  for (int i = 0; i <= 100; ++i) {
    const double x = i / 100.0, s = x * x * (3 - 2 * x);
    t.rows.push_back({x, 20 + 60 * s, 20 + 60 * s * elbow_scale});
  }
  return t;
}
}  // namespace

TEST(StaticOptimization, AMotionTheMusclesCannotMakeFailsNamingTheJointUnlessReservesHelp) {
  const auto model = fp::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) + "/models/arm_richter_warner.json");
  const std::vector<std::string> angles = {"shoulder", "elbow"};
  const fpl::StaticOptimizationResult feasible = fpl::static_optimization(*model, fp::process_coordinates_like_opensim(arm_motion(1.0), 6.0, angles));
  ASSERT_TRUE(feasible.success()) << feasible.failures.front();
  EXPECT_EQ(feasible.strength_rule, fpl::MuscleStrengthRule::RigidTendon);
  const auto fast = fp::process_coordinates_like_opensim(arm_motion(40.0), 6.0, angles);  // 2400 deg in 1 s
  const fpl::StaticOptimizationResult without = fpl::static_optimization(*model, fast);
  ASSERT_FALSE(without.success());
  const std::string& why = without.failures.front();
  EXPECT_TRUE(why.find("cannot produce the torque about 'shoulder'") != std::string::npos ||
              why.find("cannot produce the torque about 'elbow'") != std::string::npos) << why;
  fpl::StaticOptimizationOptions o;
  o.reserve_optimal_torque_N_m = 10.0;
  const fpl::StaticOptimizationResult with = fpl::static_optimization(*model, fast, o);
  EXPECT_TRUE(with.success());
  EXPECT_GT(with.reserve_torque_N_m.cwiseAbs().maxCoeff(), 1.0);
  const fp::StoTable table = fpl::static_optimization_force_table(*model, with);
  EXPECT_GE(table.columnIndex("elbow_reserve"), 0);
  for (const auto& muscle : model->description().muscles) EXPECT_GE(table.columnIndex(muscle.parameters.name), 1);
  ASSERT_EQ(table.rows.size(), with.time_s.size());
  EXPECT_EQ(table.rows[5][static_cast<std::size_t>(table.columnIndex("elbow_reserve"))], with.reserve_torque_N_m(5, 1));

  const auto partial = fp::process_coordinates_like_opensim(arm_motion(1.0, "wrist"), 6.0, std::vector<std::string>{"shoulder", "wrist"});
  try {
    fpl::static_optimization(*model, partial);
    ADD_FAILURE() << "a motion without the elbow's coordinate was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'elbow'"), std::string::npos) << e.what();
  }
  o.activation_exponent = 1.0;
  EXPECT_THROW(fpl::static_optimization(*model, fast, o), std::invalid_argument);
}

TEST(StaticOptimization, TakesTheEffortsOfTheSeamThatFitIt) {
  const auto model = fp::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) + "/models/arm_richter_warner.json");
  const auto motion = fp::process_coordinates_like_opensim(arm_motion(1.0), 6.0, std::vector<std::string>{"shoulder", "elbow"});
  // activation_cubed through the seam is OpenSim's activation_exponent 3.
  fpl::StaticOptimizationOptions cubed;
  cubed.activation_exponent = 3.0;
  fpl::StaticOptimizationOptions seam;
  seam.effort = fpl::effort_named("activation_cubed");
  const auto a = fpl::static_optimization(*model, motion, cubed), b = fpl::static_optimization(*model, motion, seam);
  ASSERT_TRUE(a.success() && b.success());
  EXPECT_LT((a.activation - b.activation).cwiseAbs().maxCoeff(), 1e-12);
  // stress_squared minimizes sum (F / Fmax)^2: its reported effort is that of its forces, and no
  // other balance of the same torques does better (a squared-activation optimum is one).
  fpl::StaticOptimizationOptions stress;
  stress.effort = fpl::effort_named("stress_squared");
  const auto s = fpl::static_optimization(*model, motion, stress);
  const auto squared = fpl::static_optimization(*model, motion);
  ASSERT_TRUE(s.success() && squared.success());
  Eigen::VectorXd Fmax(model->numMuscles());
  for (int j = 0; j < model->numMuscles(); ++j) Fmax[j] = model->description().muscles[static_cast<std::size_t>(j)].parameters.max_isometric_force_N;
  bool differs = false;
  for (Eigen::Index f = 0; f < s.effort.size(); ++f) {
    const double own = (s.tendon_force_N.row(f).transpose().cwiseQuotient(Fmax)).squaredNorm();
    const double other = (squared.tendon_force_N.row(f).transpose().cwiseQuotient(Fmax)).squaredNorm();
    EXPECT_NEAR(s.effort[f], own, 1e-9 * std::max(1.0, own));
    EXPECT_LE(own, other * (1 + 1e-9) + 1e-15) << "frame " << f;
    differs = differs || (s.activation.row(f) - squared.activation.row(f)).cwiseAbs().maxCoeff() > 1e-3;
  }
  EXPECT_TRUE(differs) << "the test needs efforts with different optima";
  fpl::StaticOptimizationOptions excitation;
  excitation.effort = fpl::effort_named("excitation_squared");
  EXPECT_THROW(fpl::static_optimization(*model, motion, excitation), std::invalid_argument);
}
