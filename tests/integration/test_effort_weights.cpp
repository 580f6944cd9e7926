// Effort weights that belong to the problem: the cost is the integral of w^T F. With constant
// moment arms and a physical w (normalized tendon forces) two valid E give the same optimal
// tendon forces, while the paper's cost (w = E^T 1) does depend on E; the reported cost is the
// integral of w^T F of the plan, evaluated here independently by quadrature of the inverse map
// (constant and posture-dependent moment arms); the receding-horizon step weighs its constant
// flat outputs by C_Y^T w.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include <Eigen/Dense>

#include "../planner/scenario_fixture.hpp"
#include "flatsos/planner/motion_planner.hpp"
#include "flatsos/planner/open_loop_study.hpp"
#include "flatsos/planner/rest_state.hpp"
#include "flatsos/plugin/io/model_file.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
using flatsos::test::deg;

namespace {

std::shared_ptr<const fp::MusculoskeletalModel> model_with_weights(const std::string& file, fp::EffortWeights w) {
  fp::ModelDescription d = fp::load_model_file(std::string(FLATSOS_SOURCE_DIR) + "/models/" + file);
  d.effort_weights = std::move(w);
  return std::make_shared<const fp::MusculoskeletalModel>(d);
}

fp::EffortWeights normalized() {
  fp::EffortWeights w;
  w.kind = fp::EffortWeights::Kind::NormalizedTendonForce;
  return w;
}

// A second valid E for the 3-muscle elbows (rows sum to 1, C invertible, Assumption 1 holds).
Eigen::MatrixXd other_E() {
  Eigen::MatrixXd E(2, 3);
  E << 0.3, 0.2, 0.5, 0.3, 0.4, 0.3;
  return E;
}

struct Planned {
  fpl::OpenLoopPlan plan;
  fpl::MuscleState start;
};

Planned plan_elbow(const fpl::FlatOutputMap& flat, const fpl::MuscleState& start, double target_deg, int spans = 1) {
  fpl::OpenLoopOptions o = fpl::open_loop_options(fpl::Preset::Paper);
  o.duration_s = 1.5;
  o.target_q_rad = Eigen::VectorXd::Constant(1, deg(target_deg));
  o.reserves_N = Eigen::VectorXd::Constant(3, 10.0);
  o.sos.flat_output_spans = spans;
  return {fpl::plan_open_loop(flat, start, o), start};
}

Eigen::VectorXd tendon_forces(const fpl::FlatOutputMap& flat, const fpl::OpenLoopPlan& plan, double t);

// The largest difference of two plans' tendon forces over [0, 1.5] s (every 10 ms).
double largest_force_gap(const fpl::FlatOutputMap& first, const fpl::OpenLoopPlan& a, const fpl::FlatOutputMap& second,
                         const fpl::OpenLoopPlan& b) {
  double worst = 0.0;
  for (int i = 0; i <= 150; ++i) {
    const double t = 0.01 * i;
    worst = std::max(worst, (tendon_forces(first, a, t) - tendon_forces(second, b, t)).cwiseAbs().maxCoeff());
  }
  return worst;
}

fpl::MuscleState rest_state(const fpl::FlatOutputMap& flat, double q_deg) {
  SimTK::State s = flat.model().defaultState();
  fpl::set_minimum_effort_rest_state(flat, s, Eigen::VectorXd::Constant(1, deg(q_deg)), Eigen::VectorXd::Constant(3, 10.0));
  return fpl::muscle_state_of(flat.model(), s);
}

Eigen::VectorXd tendon_forces(const fpl::FlatOutputMap& flat, const fpl::OpenLoopPlan& plan, double t) {
  return flat.inverse(plan.jointJet(t), plan.flatOutputJet(t)).tendon_force_N;
}

// The integral of w^T F(t) over the plan by composite Simpson on 3001 points of the inverse map.
double effort_by_quadrature(const fpl::FlatOutputMap& flat, const fpl::OpenLoopPlan& plan) {
  const int intervals = 3000;
  const double T = plan.path.duration_s, h = T / intervals;
  double sum = 0.0;
  for (int i = 0; i <= intervals; ++i) {
    const double weight = i == 0 || i == intervals ? 1.0 : i % 2 ? 4.0 : 2.0;
    sum += weight * flat.effortWeights().dot(tendon_forces(flat, plan, i * h));
  }
  return sum * h / 3.0;
}

}  // namespace

TEST(EffortWeights, ThePapersWeightsAreTheSumOfTheFlatOutputs) {
  const fpl::FlatOutputMap arm(flatsos::test::load_arm());
  ASSERT_TRUE(arm.effortIsFlatOutputSum());
  EXPECT_LT((arm.effortWeights() - arm.E().transpose() * Eigen::VectorXd::Ones(arm.numFlatOutputs())).norm(), 1e-15);
  const fpl::EffortSplit split = arm.effortSplit(Eigen::VectorXd::Zero(2));
  EXPECT_LT((split.flat_outputs - Eigen::VectorXd::Ones(4)).norm(), 1e-12);  // E C_Y = I
  EXPECT_LT(split.torques.norm(), 1e-12);                                      // E C_tau = 0
  // Normalized weights: 1 / Fmax, and a torque part that is not zero.
  const fpl::FlatOutputMap elbow(model_with_weights("elbow_1dof.json", normalized()));
  EXPECT_FALSE(elbow.effortIsFlatOutputSum());
  EXPECT_DOUBLE_EQ(elbow.effortWeights()[0], 1.0 / 1000.0);
  EXPECT_DOUBLE_EQ(elbow.effortWeights()[2], 1.0 / 700.0);
  EXPECT_GT(elbow.effortSplit(Eigen::VectorXd::Zero(1)).torques.norm(), 1e-6);
}

TEST(EffortWeights, TwoValidEGiveTheSameOptimalTendonForcesUnderAPhysicalEffortAsTheBasisGrows) {
  // With constant moment arms every E admits the same force trajectories F = C_tau tau + C_Y Y
  // as Y ranges over all functions; with Y in a spline space the particular part C_tau tau, which
  // depends on E and is not a spline, makes the classes differ. So the optimal forces of a
  // physical effort agree as the flat outputs' basis grows (measured on the 3-muscle elbow: 196 N
  // apart with the paper's one quartic span, 0.04 N with 8 spans, 0.007 N with 16).
  const auto model = model_with_weights("elbow_1dof.json", normalized());
  const fpl::FlatOutputMap first(model), second(model, other_E());
  const fpl::MuscleState start = rest_state(first, 20.0);
  const Planned a = plan_elbow(first, start, 90.0, 8), b = plan_elbow(second, start, 90.0, 8);
  ASSERT_EQ(a.plan.status, fpl::SolveStatus::Solved) << a.plan.message;
  ASSERT_EQ(b.plan.status, fpl::SolveStatus::Solved) << b.plan.message;
  EXPECT_NEAR(a.plan.sos.cost_N_s, b.plan.sos.cost_N_s, 5e-4 * a.plan.sos.cost_N_s);
  const double gap = largest_force_gap(first, a.plan, second, b.plan);
  EXPECT_LT(gap, 0.1);
  // With one span the same two E are far apart: the agreement above comes from the basis.
  const Planned a1 = plan_elbow(first, start, 90.0, 1), b1 = plan_elbow(second, start, 90.0, 1);
  ASSERT_EQ(a1.plan.status, fpl::SolveStatus::Solved) << a1.plan.message;
  ASSERT_EQ(b1.plan.status, fpl::SolveStatus::Solved) << b1.plan.message;
  EXPECT_GT(largest_force_gap(first, a1.plan, second, b1.plan), 100.0 * gap);

  // The paper's cost (w = E^T 1), by contrast, is a different effort for each E: with the same
  // rich basis the two optima stay apart.
  const auto paper_model = model_with_weights("elbow_1dof.json", fp::EffortWeights{});
  const fpl::FlatOutputMap paper_first(paper_model), paper_second(paper_model, other_E());
  const Planned pa = plan_elbow(paper_first, start, 90.0, 8), pb = plan_elbow(paper_second, start, 90.0, 8);
  ASSERT_EQ(pa.plan.status, fpl::SolveStatus::Solved) << pa.plan.message;
  ASSERT_EQ(pb.plan.status, fpl::SolveStatus::Solved) << pb.plan.message;
  EXPECT_GT(largest_force_gap(paper_first, pa.plan, paper_second, pb.plan), 100.0 * gap);
}

TEST(EffortWeights, TheReportedCostIsTheIntegralOfTheWeightedTendonForces) {
  for (const char* file : {"elbow_1dof.json", "elbow_posture_dependent.json"}) {
    fp::EffortWeights per_muscle;
    per_muscle.kind = fp::EffortWeights::Kind::PerMuscle;
    per_muscle.per_muscle = Eigen::Vector3d(1.0, 2.0, 0.5);
    for (const fp::EffortWeights& w : {normalized(), per_muscle}) {
      const fpl::FlatOutputMap flat(model_with_weights(file, w));
      const fpl::MuscleState start = rest_state(flat, 20.0);
      const Planned planned = plan_elbow(flat, start, 90.0);
      ASSERT_EQ(planned.plan.status, fpl::SolveStatus::Solved) << file << ": " << planned.plan.message;
      const double exact = effort_by_quadrature(flat, planned.plan);
      // Constant arms: exact but for the torque model's remainder (~1e-9 of it); posture-
      // dependent ones weigh the modelled coupling, within its remainder bound.
      const bool constant = flat.hasConstantMomentArms();
      EXPECT_NEAR(planned.plan.sos.cost_N_s, exact, (constant ? 1e-7 : 1e-4) * exact) << file;
    }
  }
}

TEST(EffortWeights, TheRecedingHorizonStepWeighsItsConstantFlatOutputsByTheEffort) {
  for (const char* file : {"elbow_1dof.json", "elbow_posture_dependent.json"}) {
    fp::EffortWeights w;
    w.kind = fp::EffortWeights::Kind::PerMuscle;
    w.per_muscle = Eigen::Vector3d(1.0, 0.01, 1.0);  // the brachialis' force nearly free
    const fpl::FlatOutputMap weighted(model_with_weights(file, w));
    const fpl::FlatOutputMap paper(model_with_weights(file, fp::EffortWeights{}));
    fpl::RecedingHorizonOptions o;
    o.target_q_rad = Eigen::VectorXd::Constant(1, deg(80));
    o.reserves_N = Eigen::VectorXd::Constant(3, 1.0);
    const Eigen::VectorXd q = Eigen::VectorXd::Constant(1, deg(40)), qd = Eigen::VectorXd::Zero(1);
    const fpl::RecedingHorizonStep a = fpl::plan_receding_horizon_step(weighted, q, qd, o);
    const fpl::RecedingHorizonStep b = fpl::plan_receding_horizon_step(paper, q, qd, o);
    ASSERT_EQ(a.status, fpl::SolveStatus::Solved) << a.message;
    ASSERT_EQ(b.status, fpl::SolveStatus::Solved) << b.message;
    // The weighted step's alpha is optimal for its cost: no better than the paper's alpha under
    // that cost, and the cost it reports is that cost.
    Eigen::VectorXd c = Eigen::VectorXd::Zero(2);
    if (weighted.hasConstantMomentArms()) {
      c = weighted.CY().transpose() * weighted.effortWeights();
    } else {
      for (int i = 0; i < o.grid_points; ++i) {
        fpl::Jet jet(1, 3);
        a.path.jetInto(o.horizon_s * i / (o.grid_points - 1), jet);
        c += weighted.effortSplit(jet.col(0)).flat_outputs / o.grid_points;
      }
    }
    EXPECT_NEAR(a.slp.cost_N, c.dot(a.slp.alpha), 1e-9 * (1.0 + std::abs(a.slp.cost_N))) << file;
    EXPECT_LE(c.dot(a.slp.alpha), c.dot(b.slp.alpha) + 1e-9 * (1.0 + std::abs(a.slp.cost_N))) << file;
    // Both meet every reserve row.
    EXPECT_GE((a.reserve_rows * a.slp.alpha - a.bound_N).minCoeff(), -1e-7) << file;
    // ...and they differ: the weights changed the choice.
    EXPECT_GT((a.slp.alpha - b.slp.alpha).norm(), 1e-3) << file;
  }
}

TEST(EffortWeights, AnEffortGivenWithThePlanIsTheModelFilesWeights) {
  // OpenLoopOptions::effort and FlatOutputMap::withEffort (the receding-horizon step's map)
  // plan exactly what the model file's per-muscle weights plan.
  fp::EffortWeights w;
  w.kind = fp::EffortWeights::Kind::PerMuscle;
  w.per_muscle = Eigen::Vector3d(1.0, 0.01, 1.0);
  const fpl::FlatOutputMap from_file(model_with_weights("elbow_1dof.json", w));
  const fpl::FlatOutputMap paper(model_with_weights("elbow_1dof.json", fp::EffortWeights{}));
  const auto effort = std::make_shared<fpl::TendonForceEffort>(w.per_muscle);
  const fpl::MuscleState start = rest_state(paper, 20.0);
  fpl::OpenLoopOptions o = fpl::open_loop_options(fpl::Preset::Paper);
  o.duration_s = 1.5;
  o.target_q_rad = Eigen::VectorXd::Constant(1, deg(90));
  o.reserves_N = Eigen::VectorXd::Constant(3, 10.0);
  const fpl::OpenLoopPlan expected = fpl::plan_open_loop(from_file, start, o);
  const fpl::OpenLoopPlan unweighted = fpl::plan_open_loop(paper, start, o);
  o.effort = effort;
  const fpl::OpenLoopPlan given = fpl::plan_open_loop(paper, start, o);
  ASSERT_EQ(given.status, fpl::SolveStatus::Solved) << given.message;
  ASSERT_EQ(expected.status, fpl::SolveStatus::Solved) << expected.message;
  EXPECT_NEAR(given.sos.cost_N_s, expected.sos.cost_N_s, 1e-9 * expected.sos.cost_N_s);
  EXPECT_GT(std::abs(given.sos.cost_N_s - unweighted.sos.cost_N_s), 1e-3 * unweighted.sos.cost_N_s);

  fpl::RecedingHorizonOptions rh;
  rh.target_q_rad = Eigen::VectorXd::Constant(1, deg(80));
  rh.reserves_N = Eigen::VectorXd::Constant(3, 1.0);
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(1, deg(40)), qd = Eigen::VectorXd::Zero(1);
  const fpl::RecedingHorizonStep a = fpl::plan_receding_horizon_step(paper.withEffort(effort), q, qd, rh);
  const fpl::RecedingHorizonStep b = fpl::plan_receding_horizon_step(from_file, q, qd, rh);
  ASSERT_EQ(a.status, fpl::SolveStatus::Solved) << a.message;
  EXPECT_LT((a.slp.alpha - b.slp.alpha).norm(), 1e-9 * (1.0 + b.slp.alpha.norm()));

  // A nonlinear effort is planned by its own sequential QP (test_open_loop_effort.cpp), along the
  // prescribed path and, by the reduced quasi-Newton method, with the path free; the joint Newton
  // method minimizes linear efforts only and refuses it by name.
  o.effort = fpl::effort_named("excitation_squared");
  const fpl::OpenLoopPlan squared = fpl::plan_open_loop(paper, start, o);
  ASSERT_EQ(squared.status, fpl::SolveStatus::Solved) << squared.message;
  EXPECT_EQ(squared.sos.effort_name, "excitation_squared");
  EXPECT_EQ(given.sos.effort_name, "tendon_force");
  o.free_path.enabled = true;
  fpl::OpenLoopStudyOptions study;
  study.free_path.method = fpl::FreePathMethod::JointNewton;
  try {
    fpl::plan_open_loop(paper, start, o, study);
    FAIL() << "the joint Newton method planned a nonlinear effort";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the effort 'excitation_squared' takes the method 'reduced_quasi_newton'"),
              std::string::npos)
        << e.what();
  }
  const fpl::OpenLoopPlan free = fpl::plan_open_loop(paper, start, o);
  ASSERT_EQ(free.status, fpl::SolveStatus::Solved) << free.message;
  EXPECT_TRUE(free.free_path.optimized);
  EXPECT_EQ(free.sos.effort_name, "excitation_squared");
  EXPECT_LT(free.sos.effort_value, squared.sos.effort_value);
  o.free_path.enabled = false;
  o.effort = std::make_shared<fpl::TendonForceEffort>(Eigen::Vector2d(1.0, 1.0));
  EXPECT_THROW(fpl::plan_open_loop(paper, start, o), std::invalid_argument);
}
