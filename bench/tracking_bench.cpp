#include "tracking_bench.hpp"

#include <memory>
#include <string>

#include "flatsos/planner/rest_state.hpp"
#include "flatsos/planner/static_optimization.hpp"
#include "flatsos/planner/task_region.hpp"
#include "flatsos/planner/tracking.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"
#include "default_model.hpp"
#include "timing.hpp"

namespace flatsos::bench {

namespace {

// One tracking run's timings on arm26 with each plan minimizing `effort` (null: the paper's linear
// effort), the programs' correction time.
nlohmann::json timing_with(const planner::FlatOutputMap& flat, std::shared_ptr<const planner::JointReference> reference,
                           std::shared_ptr<const planner::Effort> effort, int repetitions) {
  planner::RecedingHorizonControllerOptions options;
  options.plan.reference = reference;
  options.plan.reserves_N = Eigen::VectorXd::Constant(flat.numMuscles(), 1.0);
  options.plan.effort = effort;
  options.plan.tracking_correction_s = planner::tracking_correction_for(effort.get());  // the programs'  
  const double seconds_of_motion = reference->endTime_s() - reference->startTime_s();
  const SimTK::State initial = planner::tracking_start_state(flat, *reference, options.plan.reserves_N);
  const plugin::ClosedLoopOptions loop = planner::tracking_loop_options();

  std::vector<double> step_s, plan_s, grid_s, slp_s, bounds_s, effort_s;
  planner::TrackingRun run;
  const std::vector<double> whole = repeat(repetitions, [&] {
    planner::RecedingHorizonController controller(flat, options);
    run = planner::run_tracking(controller, initial, loop);
    for (const auto& rec : controller.history()) {
      step_s.push_back(rec.wall_seconds), plan_s.push_back(rec.plan_seconds);
      grid_s.push_back(rec.grid_seconds), slp_s.push_back(rec.slp_seconds), bounds_s.push_back(rec.bounds_seconds);
      effort_s.push_back(rec.effort_seconds);
    }
  });
  const double step_median_s = examples::median(step_s);
  constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;
  return {{"controller_step", stats(step_s, 1e3, "ms")},
          {"step_parts_median_ms",  // where a step's time goes
           {{"plan", 1e3 * examples::median(plan_s)},
            {"of_which_grid_and_rows", 1e3 * examples::median(grid_s)},
            {"of_which_slp", 1e3 * examples::median(slp_s)},
            {"of_which_first_period_bounds", 1e3 * examples::median(bounds_s)},
            {"of_which_effort_sequential_qp", 1e3 * examples::median(effort_s)},
            {"observer_and_excitations", 1e3 * (step_median_s - examples::median(plan_s))}}},
          {"controller_real_time_factor", options.control_period_s / step_median_s},
          {"closed_loop", stats(whole, 1e3, "ms")},
          {"closed_loop_real_time_factor", seconds_of_motion / examples::median(whole)},
          {"rms_error_deg", {run.rms_error[0] * kDegPerRad, run.rms_error[1] * kDegPerRad}},
          {"excitation_squared_integral", run.excitation_squared_integral},
          {"success", run.success()}};
}

}  // namespace

nlohmann::json tracking_timing(int repetitions) {
  const std::string arm26 = examples::default_model_path("opensim/arm26/");
  const auto model = std::make_shared<const plugin::MusculoskeletalModel>(
      plugin::import_opensim_file(arm26 + "arm26.osim", false, true).model);
  const auto motion = planner::read_motion_for(*model, arm26 + "inverse_kinematics/arm26_InverseKinematics.mot");
  auto reference = std::make_shared<const planner::JointReference>(planner::JointReference::fromMotion(*model, motion));
  const planner::FlatOutputMap flat =
      planner::flat_outputs_for_task(model, planner::reference_postures(*reference, motion.report_times_s));
  return {{"model", "arm26.osim, OpenSim 2.x's muscles, fitted paths (planner and plant)"},
          {"seconds_of_motion", reference->endTime_s() - reference->startTime_s()},
          {"control_period_s", planner::RecedingHorizonControllerOptions{}.control_period_s},
          {"excitation_squared", timing_with(flat, reference, planner::effort_named("excitation_squared"), repetitions)},
          {"paper_linear_effort", timing_with(flat, reference, nullptr, repetitions)}};
}

}  // namespace flatsos::bench
