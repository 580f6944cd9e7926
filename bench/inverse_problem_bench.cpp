#include "inverse_problem_bench.hpp"

#include <memory>
#include <string>
#include <vector>

#include "flatsos/planner/collocation.hpp"
#include "flatsos/planner/inverse_problem.hpp"
#include "flatsos/planner/static_optimization.hpp"
#include "flatsos/planner/task_region.hpp"
#include "flatsos/planner/tracking.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"
#include "default_model.hpp"
#include "timing.hpp"

namespace flatsos::bench {

namespace {

struct Arm26AlongMotion {
  std::shared_ptr<const plugin::MusculoskeletalModel> model;
  plugin::ProcessedCoordinates motion;
  std::shared_ptr<const planner::FlatOutputMap> flat;
};

Arm26AlongMotion arm26_along_motion(bool pennated) {
  const std::string arm26 = examples::default_model_path("opensim/arm26/");
  plugin::OpenSimFileOptions file;
  file.degroote_fregly2016_muscles = true;
  file.ignore_passive_fiber_forces = true;
  plugin::ModelDescription d = plugin::import_opensim_file(arm26 + "arm26.osim", file).model;
  if (!pennated)
    for (auto& m : d.muscles) m.parameters.pennation_angle_at_optimal_rad = 0.0;
  Arm26AlongMotion a;
  a.model = std::make_shared<const plugin::MusculoskeletalModel>(std::move(d));
  a.motion = planner::read_motion_for(*a.model, arm26 + "inverse_kinematics/arm26_InverseKinematics.mot");
  const planner::JointReference reference = planner::JointReference::fromMotion(*a.model, a.motion);
  a.flat = std::make_shared<const planner::FlatOutputMap>(
      planner::flat_outputs_for_task(a.model, planner::reference_postures(reference, a.motion.report_times_s)));
  return a;
}

nlohmann::json flatness_row(const Arm26AlongMotion& a, int repetitions, planner::InverseProblemResult& r) {
  const std::vector<double> t = repeat(repetitions, [&] { r = planner::solve_inverse_problem(*a.flat, a.motion); });
  return {{"status", planner::to_string(r.status)},
          {"message", r.message},
          {"total", stats(t, 1e3, "ms")},
          {"excitation_squared_s", r.effort_value},
          {"exchange_rounds", r.plan.sos.effort_rounds},
          {"qp_steps", r.plan.sos.effort_iterations}};
}

}  // namespace

nlohmann::json inverse_problem_timing(int repetitions) {
  nlohmann::json out = {{"model", "arm26.osim, DeGroote-Fregly muscles without passive force, fitted paths"},
                        {"motion", "OpenSim's CMC tutorial motion, 1 s, filtered at 6 Hz"}};
  planner::InverseProblemResult pennated;
  out["flatness"] = flatness_row(arm26_along_motion(true), repetitions, pennated);
  const Arm26AlongMotion unpennated = arm26_along_motion(false);
  planner::InverseProblemResult flat_r;
  nlohmann::json row = {{"flatness", flatness_row(unpennated, repetitions, flat_r)}};
  plugin::ModelWorkspace ws = unpennated.flat->makeWorkspace();
  planner::CollocationOptions o;
  o.effort = planner::effort_named("excitation_squared");
  o.mesh_intervals = 200;
  planner::CollocationResult reference;
  const std::vector<double> c = repeat(std::max(1, repetitions / 3), [&] {
    reference = planner::solve_collocation_along_motion(*unpennated.flat, ws, flat_r.plan.path,
                                                        Eigen::VectorXd::Constant(unpennated.flat->numMuscles(), 1.0), o);
  });
  row["collocation"] = {{"status", planner::to_string(reference.status)},
                        {"mesh_intervals", o.mesh_intervals},
                        {"total", stats(c, 1e3, "ms")},
                        {"ipopt_iterations", reference.iterations},
                        {"excitation_squared_s", reference.cost}};
  if (reference.status == planner::SolveStatus::Solved && flat_r.status == planner::SolveStatus::Solved) {
    row["flatness_above_collocation_percent"] = 100.0 * (flat_r.effort_value / reference.cost - 1.0);
    row["collocation_time_over_flatness_time"] =
        1e3 * examples::median(c) / row["flatness"]["total"]["median"].get<double>();  // s over ms
  }
  out["unpennated_versus_collocation"] = row;
  return out;
}

}  // namespace flatsos::bench
