#pragma once
// The paper's receding-horizon scenario, once for every test that runs it: the arm from rest at
// q = [20, 20] deg (muscles in the plant's own minimum-effort equilibrium) to [80, 80] deg,
// horizon 0.5 s on 11 points, delta = 0.05 s, reserves 1 N, exact SLP, no disturbance observer.
#include <memory>

#include "../planner/scenario_fixture.hpp"
#include "flatsos/planner/receding_horizon_controller.hpp"
#include "flatsos/planner/rest_state.hpp"

namespace flatsos::test {

struct RecedingHorizonScenario {
  std::shared_ptr<const plugin::MusculoskeletalModel> model = load_arm();  ///< the planner's model
  planner::FlatOutputMap flat{model};
  planner::RecedingHorizonControllerOptions options = default_options();
  Eigen::Vector2d start_q_rad{deg(20), deg(20)};

  static planner::RecedingHorizonControllerOptions default_options() {
    planner::RecedingHorizonControllerOptions o;
    o.plan.target_q_rad = Eigen::Vector2d(deg(80), deg(80));
    o.plan.reserves_N = Eigen::VectorXd::Constant(6, 1.0);
    o.plan.solver = planner::SlpSolver::VertexEnumeration;
    o.disturbance_observer_gain_per_s = 0.0;  // the paper's controller; tests of the observer set it
    return o;
  }

  /// The start state of `plant` (null: the planner's model), at rest in its own equilibrium.
  SimTK::State restState(std::shared_ptr<const plugin::MusculoskeletalModel> plant = nullptr) const {
    if (!plant) plant = model;
    SimTK::State s = plant->defaultState();
    planner::set_minimum_effort_rest_state(planner::FlatOutputMap(plant), s, start_q_rad, options.plan.reserves_N);
    return s;
  }

  static plugin::ClosedLoopOptions loop(double duration_s, plugin::IntegratorKind kind = plugin::IntegratorKind::RungeKuttaMerson,
                                        double accuracy = 1e-8) {
    plugin::ClosedLoopOptions o;
    o.duration_s = duration_s;
    o.integrator = kind;
    o.accuracy = accuracy;
    return o;
  }

  struct Outcome {
    std::unique_ptr<planner::RecedingHorizonController> controller;
    planner::RecedingHorizonRun run;
    double final_error_deg = 0.0;  ///< worst joint's distance from the target at the end
  };

  /// Runs a controller with `options` on `plant` (null: the planner's model) from its rest state.
  Outcome run(const plugin::ClosedLoopOptions& loop_options, std::shared_ptr<const plugin::MusculoskeletalModel> plant = nullptr,
              double settle_tolerance_rad = deg(1)) const {
    if (!plant) plant = model;
    Outcome out;
    out.controller = std::make_unique<planner::RecedingHorizonController>(flat, options, plant);
    out.run = planner::run_receding_horizon(*out.controller, restState(plant), loop_options, settle_tolerance_rad);
    const Eigen::VectorXd q = plant->jointAngles(out.run.loop.final_state);
    out.final_error_deg = (q - options.plan.target_q_rad).cwiseAbs().maxCoeff() / deg(1);
    return out;
  }
};

}  // namespace flatsos::test
