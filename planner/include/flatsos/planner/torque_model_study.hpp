#pragma once
// The torque model's study settings: the pieces' degree and how their remainders are estimated
// (torque_model.hpp). The defaults are the product's.

#include "flatsos/planner/torque_model.hpp"

namespace flatsos::planner {

struct TorqueModelStudyOptions {
  int degree = 3;                   ///< r (0 with one piece: the paper's box)
  int samples_per_piece = 16;       ///< where the remainder is sampled, ends included
  double remainder_inflation = 1.25;  ///< the sampled remainder times this
};

/// build_torque_model with study settings. Throws std::invalid_argument also for r < 0,
/// samples < 2 or fewer samples than r + 1, or an inflation below 1.
TorqueModel build_torque_model(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const JointPath& path,
                               const TorqueModelOptions& options, const TorqueModelStudyOptions& study);

}  // namespace flatsos::planner
