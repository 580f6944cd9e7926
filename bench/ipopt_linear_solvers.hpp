#pragma once
// Ipopt's linear solvers side by side in one run: flatsos's dense LDL^T and MUMPS, per Ipopt
// iteration on LPs (dense rows, the exchange's and the SLP's shape) and on the collocation
// reference (sparse), over KKT dimensions around the threshold of Automatic; and the planner's
// Ipopt-bound stages as before (MUMPS, Ipopt's getrusage timers), with flatsos's timers, and now.
#include <nlohmann/json.hpp>

#include "flatsos/planner/motion_planner.hpp"

namespace flatsos::bench {

struct LinearSolverStudyInputs {
  const planner::FlatOutputMap& flat;
  plugin::ModelWorkspace& workspace;
  const planner::MuscleState& initial;
  planner::OpenLoopOptions open_loop;  ///< the model's open-loop scenario
  Eigen::MatrixXd slp_rows;            ///< C_Y of the receding-horizon scenario's first step
  Eigen::VectorXd slp_bounds_N;        ///< its B
};

nlohmann::json ipopt_linear_solver_study(const LinearSolverStudyInputs& in, int repetitions);

}  // namespace flatsos::bench
