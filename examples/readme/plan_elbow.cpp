// Plans the elbow's flexion with the least squared excitations, as in the README.
#include <cmath>
#include <iostream>

#include "flatsos/planner/effort.hpp"
#include "flatsos/planner/open_loop.hpp"
#include "flatsos/planner/rest_state.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"

int main(int argc, char** argv) {
  namespace fp = flatsos::planner;
  const auto model = flatsos::plugin::MusculoskeletalModel::fromFile(
      argc > 1 ? argv[1] : "models/elbow_1dof.json");
  const fp::FlatOutputMap flat(model);  // the model's flat outputs and inverse map
  const Eigen::VectorXd reserves_N = Eigen::VectorXd::Constant(model->numMuscles(), 10.0);
  const Eigen::VectorXd q0_rad = Eigen::VectorXd::Constant(1, 0.0);
  const SimTK::State start =
      fp::start_state(flat, q0_rad, Eigen::VectorXd::Zero(1), std::nullopt, reserves_N);

  fp::OpenLoopOptions options;  // the best plan by default; set the task and the effort
  options.duration_s = 1.0;
  options.target_q_rad = Eigen::VectorXd::Constant(1, 60.0 * M_PI / 180.0);
  options.reserves_N = reserves_N;
  options.effort = fp::effort_named("excitation_squared");  // Moco's default goal
  const fp::OpenLoopPlan plan =
      fp::plan_open_loop(flat, fp::muscle_state_of(*model, start), options);

  std::cout << fp::to_string(plan.status) << ": " << plan.sos.effort_value << " s\n";
  return plan.status == fp::SolveStatus::Solved ? 0 : 1;
}
