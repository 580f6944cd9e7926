// A second effort end to end: the collocation reference minimizes OpenSim Moco's default effort,
// the integral of squared excitations, along the flatness plan's joint path on the 3-muscle
// elbow, beside the paper's linear effort. Each optimum is checked against the other's
// excitations and forces on the same quadrature (neither optimum may be beaten under its own
// effort), and the squared effort shares the load between the two flexors where the linear one
// leaves the brachialis at its reserve.
#include <gtest/gtest.h>

#include <iostream>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "flatsos/planner/collocation.hpp"
#include "flatsos/planner/effort.hpp"
#include "flatsos/planner/motion_planner.hpp"
#include "flatsos/planner/rest_state.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/model/model_workspace.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;

namespace {

// Simpson's weights of the collocation points (2K + 1 uniform points).
Eigen::VectorXd simpson_weights(const Eigen::VectorXd& t) {
  const int P = static_cast<int>(t.size());
  const double h = (t[P - 1] - t[0]) / ((P - 1) / 2);
  Eigen::VectorXd w(P);
  for (int i = 0; i < P; ++i) w[i] = (i % 2 == 1 ? 4.0 : (i == 0 || i == P - 1 ? 1.0 : 2.0)) * h / 6.0;
  return w;
}

double squared_excitations(const fpl::CollocationResult& r) {
  return simpson_weights(r.time_s).dot(r.excitation.array().square().matrix().colwise().sum().transpose());
}
double weighted_forces(const fpl::CollocationResult& r, const Eigen::VectorXd& w) {
  return simpson_weights(r.time_s).dot((w.transpose() * r.tendon_force_N).transpose());
}

}  // namespace

TEST(SecondEffort, SquaredExcitationsShareTheLoadAndEachOptimumBeatsTheOther) {
  const fp::ModelDescription d = fp::load_model_file(std::string(FLATSOS_SOURCE_DIR) + "/models/elbow_1dof.json");
  const auto model = std::make_shared<const fp::MusculoskeletalModel>(d);
  const fpl::FlatOutputMap flat(model);
  const fp::ScenarioDescription& s = *d.scenario("open_loop");
  const Eigen::VectorXd reserves = Eigen::VectorXd::Constant(3, s.reserves_N[0]);
  SimTK::State state = model->defaultState();
  fpl::set_minimum_effort_rest_state(flat, state, s.q0_rad, reserves);
  const fpl::MuscleState s0 = fpl::muscle_state_of(*model, state);
  fpl::OpenLoopOptions o = fpl::open_loop_options(fpl::Preset::Paper);
  o.duration_s = s.duration_s;
  o.target_q_rad = s.target_q_rad;
  o.reserves_N = reserves;
  o.sos.flat_output_spans = 12;
  const fpl::OpenLoopPlan plan = fpl::plan_open_loop(flat, s0, o);
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;

  fp::ModelWorkspace workspace(*model);
  fpl::CollocationOptions linear_options;
  linear_options.mesh_intervals = 50;
  const fpl::CollocationResult linear =
      fpl::solve_collocation_along_path(flat, workspace, plan.path, s0, reserves, linear_options);
  fpl::CollocationOptions squared_options = linear_options;
  squared_options.effort = fpl::effort_named("excitation_squared");
  const fpl::CollocationResult squared =
      fpl::solve_collocation_along_path(flat, workspace, plan.path, s0, reserves, squared_options);
  ASSERT_EQ(linear.status, fpl::SolveStatus::Solved) << linear.message;
  ASSERT_EQ(squared.status, fpl::SolveStatus::Solved) << squared.message;
  EXPECT_EQ(linear.cost_unit, "N s");
  // The deprecated spelling (per-muscle weights, cost_N_s) plans the same.
  fpl::CollocationOptions deprecated = linear_options;
  deprecated.effort_weights = flat.effortWeights();
  const fpl::CollocationResult old = fpl::solve_collocation_along_path(flat, workspace, plan.path, s0, reserves, deprecated);
  EXPECT_NEAR(old.cost_N_s, linear.cost, 1e-9 * linear.cost);
  EXPECT_EQ(squared.cost_unit, "s");

  // The reported costs are the efforts' quadratures, and each optimum beats the other's solution
  // under its own effort.
  const Eigen::VectorXd w = flat.effortWeights();
  EXPECT_NEAR(squared.cost, squared_excitations(squared), 1e-9 * squared.cost);
  EXPECT_NEAR(linear.cost, weighted_forces(linear, w), 1e-9 * linear.cost);
  const double squared_of_linear = squared_excitations(linear), linear_of_squared = weighted_forces(squared, w);
  std::cout << "elbow, squared excitations: " << squared.cost << " s (the linear optimum's excitations: "
            << squared_of_linear << " s) in " << squared.iterations << " iterations; tendon forces: " << linear.cost
            << " N s (the squared optimum's: " << linear_of_squared << " N s)\n";
  EXPECT_LT(squared.cost, squared_of_linear * (1.0 - 1e-3));
  EXPECT_LT(linear.cost, linear_of_squared * (1.0 - 1e-3));

  // Load sharing: the linear effort leaves the brachialis (muscle 1) at its reserve for the whole
  // motion (a vertex of its linear program); the squared effort has it carry more than its
  // reserve over much of it (measured: 55 % of the points, up to 27 N against the reserve's 10 N).
  const double reserve = reserves[1];
  auto share_above_reserve = [&](const fpl::CollocationResult& r) {
    return (r.tendon_force_N.row(1).array() > reserve * 1.05).cast<double>().mean();
  };
  std::cout << "  brachialis above its reserve at " << 100.0 * share_above_reserve(linear) << " % (linear) and "
            << 100.0 * share_above_reserve(squared) << " % (squared) of the points; its largest force "
            << linear.tendon_force_N.row(1).maxCoeff() << " N and " << squared.tendon_force_N.row(1).maxCoeff() << " N\n";
  EXPECT_LT(linear.tendon_force_N.row(1).maxCoeff(), reserve * 1.001);
  EXPECT_GT(share_above_reserve(squared), 0.4);
  EXPECT_GT(squared.tendon_force_N.row(1).maxCoeff(), 2.0 * reserve);
}
