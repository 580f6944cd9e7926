// Tracking a joint motion with the receding-horizon controller (tracking.hpp): the reference,
// the horizon's path and the flat outputs' start by their defining properties, and OpenSim's CMC
// tutorial motion on arm26 followed by the controller.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "flatsos/planner/rest_state.hpp"
#include "flatsos/planner/task_region.hpp"
#include "flatsos/planner/tracking.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"
#include "flatsos/plugin/io/sto_file.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;
const std::string kArm26 = std::string(FLATSOS_SOURCE_DIR) + "/models/opensim/arm26/";

// arm26 with OpenSim 2.x's muscles (those of the tutorial's CMC run), planned and simulated with
// its fitted paths.
std::shared_ptr<const fp::MusculoskeletalModel> arm26_opensim2() {
  static std::shared_ptr<const fp::MusculoskeletalModel> model;
  if (!model)
    model = std::make_shared<const fp::MusculoskeletalModel>(fp::import_opensim_file(kArm26 + "arm26.osim", false, true).model);
  return model;
}

const fp::ProcessedCoordinates& tutorial_motion() {
  static const fp::ProcessedCoordinates motion = fp::process_coordinates_like_opensim(
      fp::read_sto(kArm26 + "inverse_kinematics/arm26_InverseKinematics.mot"), 6.0,
      std::vector<std::string>{"r_shoulder_elev", "r_elbow_flex"});
  return motion;
}

struct Tracked {
  fpl::TrackingRun run;
  int clamps = 0, plan_failures = 0, steps = 0, free_starts = 0;
};

// The tutorial's motion tracked from its first state (muscles at the minimum-effort rest there),
// with the programs' correction time (track_motion, flatsos.track).
Tracked track_arm26(double plant_strength, std::shared_ptr<const fpl::Effort> effort = nullptr) {
  auto model = arm26_opensim2();
  auto reference = std::make_shared<const fpl::JointReference>(fpl::JointReference::fromMotion(*model, tutorial_motion()));
  const fpl::FlatOutputMap flat =
      fpl::flat_outputs_for_task(model, fpl::reference_postures(*reference, tutorial_motion().report_times_s));
  fpl::RecedingHorizonControllerOptions o;
  o.plan.reference = reference;
  o.plan.reserves_N = Eigen::VectorXd::Constant(model->numMuscles(), 1.0);
  o.plan.effort = effort;
  o.plan.tracking_correction_s = fpl::tracking_correction_for(effort.get());
  std::shared_ptr<const fp::MusculoskeletalModel> plant;
  if (plant_strength != 1.0) {
    fp::ModelDescription d = model->description();
    for (auto& m : d.muscles) m.parameters.max_isometric_force_N *= plant_strength;
    plant = std::make_shared<const fp::MusculoskeletalModel>(std::move(d));
  }
  fpl::RecedingHorizonController controller(flat, o, plant);
  const SimTK::State s = fpl::tracking_start_state(plant ? flat.withModel(plant) : flat, *reference, o.plan.reserves_N);
  Tracked out;
  out.run = fpl::run_tracking(controller, s, fpl::tracking_loop_options(), 0.5 * kDeg);
  out.clamps = controller.clampedSamples();
  out.plan_failures = controller.planFailures();
  out.steps = controller.steps();
  for (const auto& rec : controller.history())
    if (!rec.free_start_message.empty()) ++out.free_starts, std::printf("free start at %g s: %s\n", rec.time_s, rec.free_start_message.c_str());
  std::printf("tracking arm26 (plant strength %.2f, effort %s): RMS %.4f %.4f deg, max %.4f %.4f deg, integral of sum u^2 %.4f, "
              "%d steps, %d clamps, %d failures\n",
              plant_strength, effort ? effort->name().c_str() : "tendon_force", out.run.rms_error[0] / kDeg, out.run.rms_error[1] / kDeg, out.run.max_abs_error[0] / kDeg,
              out.run.max_abs_error[1] / kDeg, out.run.excitation_squared_integral, out.steps, out.clamps, out.plan_failures);
  for (const auto& f : out.run.failures) std::printf("  %s\n", f.c_str());
  return out;
}

// The front ends' default: each plan minimizing its squared excitations (run once, shared).
const Tracked& arm26_squared() {
  static const Tracked t = track_arm26(1.0, fpl::effort_named("excitation_squared"));
  return t;
}

}  // namespace

TEST(JointReference, AMeasuredMotionIsItsSplinesAndGoesOnPastItsEnds) {
  auto model = arm26_opensim2();
  const fpl::JointReference r = fpl::JointReference::fromMotion(*model, tutorial_motion());
  ASSERT_EQ(r.numJoints(), 2);
  EXPECT_DOUBLE_EQ(r.startTime_s(), tutorial_motion().report_times_s.front());
  EXPECT_DOUBLE_EQ(r.endTime_s(), tutorial_motion().report_times_s.back());
  // Joint order is the model's, whatever the file's column order.
  const double t = 0.37;
  EXPECT_DOUBLE_EQ(r.derivative(1, t, 0), tutorial_motion().spline("r_elbow_flex").value(t));
  EXPECT_DOUBLE_EQ(r.derivative(1, t, 2), tutorial_motion().spline("r_elbow_flex").secondDerivative(t));
  // Past the last knot the last interval continues: value and slope without a jump.
  const fp::NaturalQuinticSpline unfiltered({0.0, 0.1, 0.2, 0.3, 0.4, 0.5}, {0.0, 0.3, 0.1, 0.4, 0.2, 0.5});
  for (int k = 0; k <= 4; ++k) {
    EXPECT_NEAR(unfiltered.continuedDerivative(0.5 + 1e-9, k), unfiltered.derivative(0.5, k), 1e-5 * (1.0 + std::pow(10.0, k)));
    EXPECT_NEAR(unfiltered.continuedDerivative(-1e-9, k), unfiltered.derivative(0.0, k), 1e-5 * (1.0 + std::pow(10.0, k)));
  }
  EXPECT_THROW(unfiltered.derivative(0.6, 0), std::invalid_argument);
  EXPECT_TRUE(std::isfinite(unfiltered.continuedDerivative(0.6, 0)));
  fp::ProcessedCoordinates lacking = tutorial_motion();
  lacking.names[0] = "elsewhere";
  lacking.names[1] = "elsewhere_too";
  EXPECT_THROW(fpl::JointReference::fromMotion(*model, lacking), std::invalid_argument);
}

TEST(JointReference, APlanRestsAtItsEndPosture) {
  fpl::JointPath path = fpl::fit_joint_path(0.5, (Eigen::MatrixXd(1, 2) << 0.1, 0.0).finished(),
                                             (Eigen::MatrixXd(1, 2) << 0.7, 0.0).finished());
  const fpl::JointReference r = fpl::JointReference::fromPath(path, 2.0);
  EXPECT_NEAR(r.derivative(0, 2.0, 0), 0.1, 1e-12);
  EXPECT_NEAR(r.derivative(0, 2.25, 0), path.jet(0.25, 1)(0, 0), 1e-12);
  EXPECT_NEAR(r.derivative(0, 3.0, 0), 0.7, 1e-12);
  EXPECT_EQ(r.derivative(0, 3.0, 1), 0.0);
  EXPECT_NEAR(r.derivative(0, 1.0, 0), 0.1, 1e-12);  // before its start: at its start, at rest
  EXPECT_EQ(r.derivative(0, 1.0, 2), 0.0);
  EXPECT_THROW(fpl::JointReference::fromPath(fpl::JointPath{}, 0.0), std::invalid_argument);
}

TEST(TrackingPath, StartsAtTheStateAndJoinsTheReferenceAtTheCorrectionTime) {
  auto model = arm26_opensim2();
  auto reference = std::make_shared<const fpl::JointReference>(fpl::JointReference::fromMotion(*model, tutorial_motion()));
  const double t0 = 0.4, T = 0.5, Tc = 0.1;
  const Eigen::Vector2d q(0.02, 0.9), qd(-0.1, 1.5), qdd(0.3, -2.0), qddd(4.0, 10.0);
  for (const bool with_start : {false, true}) {
    fpl::JointPath path;
    fpl::fit_tracking_path(T, Tc, q, qd, with_start ? Eigen::VectorXd(qdd) : Eigen::VectorXd(),
                           with_start ? Eigen::VectorXd(qddd) : Eigen::VectorXd(), reference, t0, path);
    const fpl::Jet start = path.jet(0.0, 4);
    EXPECT_LT((start.col(0) - q).norm(), 1e-12);
    EXPECT_LT((start.col(1) - qd).norm(), 1e-12);
    if (with_start) {
      EXPECT_LT((start.col(2) - qdd).norm(), 1e-9);
      EXPECT_LT((start.col(3) - qddd).norm(), 1e-8);
    }
    // At and after the correction time: the reference's value, speed, acceleration and jerk.
    for (double s : {Tc, Tc + 1e-7, 0.3, T}) {
      const fpl::Jet p = path.jet(s, 4), r = reference->jet(t0 + s, 4);
      EXPECT_LT((p - r).cwiseAbs().maxCoeff(), 1e-5) << "s = " << s << (with_start ? " (with start)" : "");
    }
  }
  fpl::JointPath path;
  EXPECT_THROW(fpl::fit_tracking_path(T, 0.6, q, qd, {}, {}, reference, t0, path), std::invalid_argument);
  EXPECT_THROW(fpl::fit_tracking_path(T, Tc, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), {}, {}, reference, t0, path),
               std::invalid_argument);
}

TEST(FlatOutputStart, BlendsFromTheStartToAlphaWithExactDerivatives) {
  fpl::FlatOutputStart start;
  start.value = Eigen::Vector2d(10.0, 40.0);
  start.rate = Eigen::Vector2d(-50.0, 80.0);
  start.blend_s = 0.1;
  const Eigen::Vector2d alpha(25.0, 30.0);
  fpl::Jet y(2, 3);
  start.jetInto(alpha, 0.0, y);
  EXPECT_LT((y.col(0) - start.value).norm(), 1e-12);
  EXPECT_LT((y.col(1) - start.rate).norm(), 1e-12);
  // The start's curvature leaves the first excitation to alpha: -12 (value - alpha) / T^2 ...
  EXPECT_LT((y.col(2) - (-12.0 * (start.value - alpha) / 0.01 - 6.0 * start.rate / 0.1)).norm(), 1e-9);
  for (double t : {0.1, 0.15}) {
    start.jetInto(alpha, t, y);
    EXPECT_LT((y.col(0) - alpha).norm(), 1e-12);
    EXPECT_LT(y.rightCols(2).norm(), 1e-9);
  }
  // Derivatives against central differences inside the blend.
  for (double t : {0.013, 0.05, 0.087}) {
    const double h = 1e-6;
    fpl::Jet a(2, 3), b(2, 3);
    start.jetInto(alpha, t, y);
    start.jetInto(alpha, t - h, a);
    start.jetInto(alpha, t + h, b);
    EXPECT_LT(((b.col(0) - a.col(0)) / (2 * h) - y.col(1)).norm(), 1e-5 * (1.0 + y.col(1).norm()));
    EXPECT_LT(((b.col(1) - a.col(1)) / (2 * h) - y.col(2)).norm(), 1e-4 * (1.0 + y.col(2).norm()));
  }
}

TEST(Tracking, Arm26FollowsTheCmcTutorialsMotion) {
  const Tracked& t = arm26_squared();
  EXPECT_TRUE(t.run.success());
  EXPECT_EQ(t.plan_failures, 0);
  EXPECT_EQ(t.clamps, 0);  // excitations within [0, 1] by the step's bounds
  EXPECT_EQ(t.steps, 20);
  EXPECT_EQ(t.free_starts, 0);  // every plan started from the muscles' states
  // Measured 0.013 and 0.046 deg (the issue asks for 0.05). Plans that start from their own
  // muscle states instead: 0.77 and 0.68 deg with a 0.2 s correction, and most plans fail with
  // 0.1 s. What is left is mostly the plant's own velocity law (OpenSim 2.x's damped one), which
  // the plans invert undamped.
  EXPECT_LE(t.run.rms_error[0], 0.025 * kDeg);
  EXPECT_LE(t.run.rms_error[1], 0.05 * kDeg);
  ASSERT_EQ(t.run.position_errors.rows.size(), t.run.loop.states.rows.size());
  EXPECT_EQ(t.run.position_errors.columns, (std::vector<std::string>{"time", "r_shoulder_elev", "r_elbow_flex"}));
}

TEST(Tracking, Arm26WithAPlantOneFifthWeaker) {
  const Tracked t = track_arm26(0.8, fpl::effort_named("excitation_squared"));
  EXPECT_TRUE(t.run.success());
  EXPECT_EQ(t.plan_failures, 0);
  EXPECT_LE(t.run.max_abs_error.maxCoeff(), 0.5 * kDeg);  // measured 0.17 deg
}

TEST(Tracking, Arm26WithSquaredExcitationsSharesTheLoadAndCostsLess) {
  // The paper's linear effort: 0.334 (measured, at its 0.075 s correction). Each step
  // minimizing the integral of the squared excitations over its horizon instead: 0.247. The
  // per-frame minimum of sum a^2 along the motion with the muscles' passive forces counted (a
  // rigid-tendon static optimization) is 0.162 (docs/method/receding_horizon.md: the gap).
  const Tracked linear = track_arm26(1.0);
  const Tracked& squared = arm26_squared();
  EXPECT_TRUE(squared.run.success());
  EXPECT_EQ(squared.plan_failures, 0);
  EXPECT_EQ(squared.clamps, 0);
  EXPECT_EQ(squared.free_starts, 0);
  EXPECT_LE(squared.run.excitation_squared_integral, 0.75 * linear.run.excitation_squared_integral);
  EXPECT_LE(squared.run.excitation_squared_integral, 0.26);
}

TEST(Tracking, RefusesAControllerWithoutAReference) {
  auto model = arm26_opensim2();
  auto reference = std::make_shared<const fpl::JointReference>(fpl::JointReference::fromMotion(*model, tutorial_motion()));
  std::vector<Eigen::VectorXd> postures = {reference->jet(0.0, 1).col(0), reference->jet(1.0, 1).col(0)};
  const fpl::FlatOutputMap flat = fpl::flat_outputs_for_task(model, postures);
  fpl::RecedingHorizonControllerOptions o;
  o.plan.target_q_rad = postures.back();
  o.plan.reserves_N = Eigen::VectorXd::Constant(model->numMuscles(), 1.0);
  fpl::RecedingHorizonController set_point(flat, o);
  // The motion's first frame (its elbow 0.05 deg outside the joint's range, as measured motions
  // may be): the tracking start, which start_state would refuse as a transfer's start.
  SimTK::State s = fpl::tracking_start_state(flat, *reference, o.plan.reserves_N);
  EXPECT_THROW(fpl::start_state(flat, postures.front(), Eigen::Vector2d::Zero(), std::nullopt, o.plan.reserves_N),
               std::invalid_argument);
  EXPECT_THROW(fpl::run_tracking(set_point, s, {}), std::invalid_argument);
  o.plan.reference = reference;
  o.plan.target_q_rad.resize(0);  // not needed when tracking
  fpl::RecedingHorizonController tracker(flat, o);
  s.setTime(2.0);  // after the reference's end
  EXPECT_THROW(fpl::run_tracking(tracker, s, {}), std::invalid_argument);
}

TEST(Tracking, APlantOfOtherStrengthsKeepsEveryTendonTautOverTheFirstPeriod) {
  // The paper's arm through a smooth 40 deg swing of both joints, on a plant whose muscles are
  // 0.9-1.1 times as strong (a Dask study's sample). Without reserve rows on the first period's
  // samples, a plan that starts from the muscles' states let the long triceps go slack there
  // (-0.3 N): 16 of the 20 plans failed and the elbow ended 30 deg away.
  auto model = std::make_shared<const fp::MusculoskeletalModel>(
      fp::load_model_file(std::string(FLATSOS_SOURCE_DIR) + "/models/arm_richter_warner.json"));
  fp::StoTable swing;
  swing.in_degrees = true;
  swing.columns = {"time", "shoulder", "elbow"};
  for (int i = 0; i <= 100; ++i) {
    const double x = i / 100.0, s = x * x * (3.0 - 2.0 * x);
    swing.rows.push_back({x, 30.0 + 40.0 * s, 40.0 + 40.0 * s});
  }
  const fp::ProcessedCoordinates motion =
      fp::process_coordinates_like_opensim(swing, 6.0, std::vector<std::string>{"shoulder", "elbow"});
  auto reference = std::make_shared<const fpl::JointReference>(fpl::JointReference::fromMotion(*model, motion));
  const fpl::FlatOutputMap flat(model);
  fpl::RecedingHorizonControllerOptions o;
  o.plan.reference = reference;
  o.plan.reserves_N = Eigen::VectorXd::Constant(model->numMuscles(), 1.0);
  fp::ModelDescription d = model->description();
  const double factors[] = {1.039, 0.959, 0.9, 1.095, 0.96, 0.963};
  for (std::size_t j = 0; j < d.muscles.size(); ++j) d.muscles[j].parameters.max_isometric_force_N *= factors[j];
  auto plant = std::make_shared<const fp::MusculoskeletalModel>(std::move(d));
  fpl::RecedingHorizonController controller(flat, o, plant);
  const SimTK::State s = fpl::tracking_start_state(flat.withModel(plant), *reference, o.plan.reserves_N);
  const fpl::TrackingRun run = fpl::run_tracking(controller, s, fpl::tracking_loop_options(), 2.0 * kDeg);
  EXPECT_TRUE(run.success()) << (run.failures.empty() ? "" : run.failures.front());
  EXPECT_EQ(controller.planFailures(), 0);
  int free_starts = 0;
  for (const auto& rec : controller.history()) free_starts += rec.free_start_message.empty() ? 0 : 1;
  EXPECT_LE(free_starts, 1);  // the first plan, at the rest state (see the method's notes)
  EXPECT_LE(run.rms_error.maxCoeff(), 0.5 * kDeg);
}
