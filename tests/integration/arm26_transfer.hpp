#pragma once
// OpenSim's arm26 (from the repository's models) flexing the elbow from 0 to 90 deg in 1 s from
// rest with 10 N reserves: its flat outputs for the task, the rest state and the plan's options
// (the default basis). Its muscles as downloaded (Thelen) or as the file options replace them.
#include <Eigen/Core>
#include <cmath>
#include <memory>
#include <optional>
#include <string>

#include "flatsos/planner/motion_planner.hpp"
#include "flatsos/planner/rest_state.hpp"
#include "flatsos/planner/task_region.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"

namespace flatsos::test {

struct Arm26Transfer {
  std::shared_ptr<const plugin::MusculoskeletalModel> model;
  std::optional<planner::FlatOutputMap> flat;
  SimTK::State rest;        // the minimum-effort rest at q = 0 (the muscles near their floor)
  planner::MuscleState s0;  // the same as the planner's muscle state
  planner::OpenLoopOptions options;
};

inline Arm26Transfer arm26_transfer(const plugin::OpenSimFileOptions& file = {}) {
  Arm26Transfer a;
  a.model = std::make_shared<const plugin::MusculoskeletalModel>(
      plugin::import_opensim_file(
          std::string(FLATSOS_SOURCE_DIR) + "/models/opensim/arm26/arm26.osim", file)
          .model);
  const Eigen::VectorXd q0 = Eigen::Vector2d::Zero();
  const Eigen::Vector2d target(0.0, 90.0 * M_PI / 180.0);
  a.flat.emplace(planner::flat_outputs_for_task(a.model, {q0, target}));
  a.options.duration_s = 1.0;
  a.options.target_q_rad = target;
  a.options.reserves_N = Eigen::VectorXd::Constant(6, 10.0);
  a.rest = planner::start_state(*a.flat, q0, Eigen::Vector2d::Zero(), std::nullopt,
                                a.options.reserves_N);
  a.s0 = planner::muscle_state_of(*a.model, a.rest);
  return a;
}

}  // namespace flatsos::test
