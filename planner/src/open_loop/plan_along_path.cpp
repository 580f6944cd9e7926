#include "open_loop/plan_along_path.hpp"

#include <string>
#include <utility>

#include "flatsos/plugin/stopwatch.hpp"

namespace flatsos::planner::detail {

void plan_along_path(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const FlatOutputBoundary& bc,
                     const OpenLoopOptions& o, const OpenLoopStudyOptions& study, OpenLoopPlan& plan,
                     const BoundsWarmStart* warm) {
  const Stopwatch setup;
  if (!flat.hasConstantMomentArms()) {
    // C(q(t)) must satisfy Assumption 1 all along the path, not only in the ranges' grid: checked
    // as densely as the torque model samples it.
    const int points = o.torque.pieces * (study.torque.samples_per_piece - 1) + 1;
    for (int i = 0; i < points; ++i) {
      const double t = plan.path.duration_s * i / (points - 1);
      const std::string failure = flat.assumption1FailureAt(plan.path.jet(t, 1).col(0));
      if (failure.empty()) continue;
      plan.status = SolveStatus::Infeasible;
      plan.message = "the joint path leaves the postures where the flat outputs are valid, at t = " + std::to_string(t) +
                     " s " + failure;
      return;
    }
  }
  plan.torque = build_torque_model(flat, workspace, plan.path, o.torque, study.torque);
  const double before_sos = setup.seconds();
  const MusclesAlongPath muscles{flat, plan.path, workspace};
  plan.sos = warm ? solve_sos_program_from(flat, plan.torque, o.duration_s, bc, o.reserves_N,
                                                   sos_settings(o.sos, study.sos), muscles, *warm)
                  : solve_sos_program(flat, plan.torque, o.duration_s, bc, o.reserves_N, o.sos, study.sos, &muscles);
  plan.setup_seconds = before_sos + plan.sos.setup_seconds;
  plan.solve_seconds = plan.sos.solve_seconds;
  plan.certify_seconds = plan.sos.certify_seconds;
  plan.status = plan.sos.status;
  plan.message = plan.sos.message;
  if (plan.status == SolveStatus::Infeasible && plan.sos.bounds_imposed && plan.sos.Y) {
    // The bounds cannot be met: say where the closest plan leaves the muscles' domain.
    auto closest = check_plan(flat, workspace, plan.path, *plan.sos.Y, o.reserves_N, o.check_points, study.sos.bounds.tolerance);
    if (!closest.limiting_violation.empty())
      plan.message += "; the closest plan leaves the model's valid domain: " + closest.limiting_violation;
    plan.check = std::move(closest);
    return;
  }
  if (plan.status != SolveStatus::Solved) return;
  plan.Y = plan.sos.Y;

  const Stopwatch check;
  plan.check = check_plan(flat, workspace, plan.path, *plan.Y, o.reserves_N, o.check_points,
                          o.sos.bounds.enforce ? study.sos.bounds.tolerance : 0.0);
  plan.check_seconds = check.seconds();
  if (plan.check.min_reserve_margin_N < -1e-6) {
    plan.status = SolveStatus::Failed;
    plan.message = "the plan violates a tendon-force reserve on the check grid by " +
                   std::to_string(-plan.check.min_reserve_margin_N) + " N (torque-model remainder underestimated)";
  } else if (plan.check.points_outside_domain > 0) {
    // The SOS program was solved, but the muscles cannot execute the plan (a > 1, n outside
    // [0, 1], u >= Vmax, ...): not a usable plan.
    plan.status = SolveStatus::Infeasible;
    plan.message = "the plan leaves the model's valid domain: " + plan.check.limiting_violation + "; at " +
                   std::to_string(plan.check.points_outside_domain) + " of " + std::to_string(plan.check.points) +
                   " check points, the first at " + plan.check.first_violation;
  }
}

}  // namespace flatsos::planner::detail
