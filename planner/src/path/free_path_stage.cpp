#include "path/free_path_stage.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "bounds/bound_rows.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "open_loop/plan_along_path.hpp"
#include "path/free_path.hpp"
#include "path/free_path_settings.hpp"

namespace flatsos::planner {

FreePathMethod free_path_method(const std::string& name) {
  for (const FreePathMethod m : {FreePathMethod::ReducedQuasiNewton, FreePathMethod::JointNewton})
    if (name == to_string(m)) return m;
  throw std::invalid_argument("free path method '" + name + "': expected 'reduced_quasi_newton' or 'joint_newton'");
}

namespace detail {

void validate_free_path_options(const FlatOutputMap& flat, const OpenLoopOptions& o, const OpenLoopStudyOptions& study) {
  if (!o.free_path.enabled) return;
  const FreePathSettings f(o.free_path, study.free_path);
  if (!flat.hasConstantMomentArms())
    throw std::invalid_argument("open-loop plan: free_path needs constant moment arms; model '" +
                                flat.model().description().name + "' has posture-dependent ones (plan along the "
                                "prescribed path instead)");
  if (!flat.effortIsFlatOutputSum())
    throw std::invalid_argument("open-loop plan: free_path minimizes the sum of the flat outputs; model '" +
                                flat.model().description().name + "' weighs its effort otherwise (effort_weights), whose "
                                "torque part w^T C_tau tau changes with the path (plan along the prescribed path instead)");
  if (!o.sos.bounds.enforce)
    throw std::invalid_argument("open-loop plan: free_path needs the excitation bounds (sos.bounds.enforce): without "
                                "them a faster path always costs less");
  if (o.sos.effort && study.free_path.method == FreePathMethod::JointNewton)
    throw std::invalid_argument("open-loop plan: the free path's joint Newton method minimizes efforts linear in the "
                                "tendon forces; the effort '" + o.sos.effort->name() + "' takes the method '" +
                                to_string(FreePathMethod::ReducedQuasiNewton) + "'");
  if (study.sos.method != SosProgramMethod::Exchange)
    throw std::invalid_argument(std::string("open-loop plan: free_path plans by the exchange method, which imposes the "
                                            "excitation bounds; sos.method '") +
                                to_string(study.sos.method) + "' only checks them");
  if (f.degree < 5) throw std::invalid_argument("open-loop plan: free_path.degree must be >= 5 (q'''' continuous)");
  if (f.spans < 1 || f.degree + f.spans - 9 < 1)
    throw std::invalid_argument("open-loop plan: free_path.degree + free_path.spans must be >= 10 (9 boundary "
                                "derivatives per joint and at least one free coefficient)");
  if (!(f.span_growth > 0.0) || !std::isfinite(f.span_growth))
    throw std::invalid_argument("open-loop plan: free_path.span_growth must be finite and > 0 (1: uniform spans)");
  if (f.points_per_span < 1) throw std::invalid_argument("open-loop plan: free_path.points_per_span must be >= 1");
  if (f.start_min_spans < 0) throw std::invalid_argument("open-loop plan: free_path.start_min_spans must be >= 0");
  if (f.check_points < 2) throw std::invalid_argument("open-loop plan: free_path.check_points must be >= 2");
  if (!(f.tolerance >= 0.0) || !(f.tolerance_N >= 0.0))
    throw std::invalid_argument("open-loop plan: free_path tolerances must be >= 0");
  if (!(f.relative_tolerance > 0.0)) throw std::invalid_argument("open-loop plan: free_path.relative_tolerance must be > 0");
  if (!(f.exchange_relative_tolerance >= 0.0) || !std::isfinite(f.exchange_relative_tolerance))
    throw std::invalid_argument("open-loop plan: free_path.exchange_relative_tolerance must be finite and >= 0");
  if (f.max_rounds < 1 || f.max_path_iterations < 1 || f.max_sequential_lp_iterations < 1)
    throw std::invalid_argument("open-loop plan: free_path.max_rounds, max_path_iterations and max_sequential_lp_iterations must be >= 1");
  if (f.max_torque_refinements < 0 || f.max_torque_refinements > 10)
    throw std::invalid_argument("open-loop plan: free_path.max_torque_refinements must be in [0, 10] (each doubles "
                                "the torque pieces)");
  if (!(f.torque_model_relative_gap >= 0.0) || !std::isfinite(f.torque_model_relative_gap))
    throw std::invalid_argument("open-loop plan: free_path.torque_model_relative_gap must be finite and >= 0");
}

int start_flat_output_spans(int spans, int min_spans, int fewest) {
  if (min_spans == 0) return spans;
  for (int f = spans; f > 1; --f)
    if (spans % f == 0 && spans / f >= std::max(min_spans, fewest)) return spans / f;
  return spans;
}

namespace {

// The path stage from the prescribed plan (its flat outputs carried into the options' basis).
FreePathOutcome optimize_path(const FlatOutputMap& flat, const Eigen::MatrixXd& initial_q_jet,
                              const OpenLoopOptions& o, const OpenLoopStudyOptions& study, int start_spans,
                              const OpenLoopPlan& plan, const SosSetup& program) {
  const Eigen::VectorXd a_min = activation_minima(flat, o.sos.bounds.min_activation);
  const SplineTrajectory start_Y =
      start_spans == o.sos.flat_output_spans ? *plan.sos.Y : plan.sos.Y->inBasis(program.basis);
  FreePathSettings settings(o.free_path, study.free_path);
  settings.effort = o.sos.effort.get();
  return optimize_joint_path(program, flat, plan.path, initial_q_jet, o.target_q_rad, theta_of(program, start_Y),
                             o.reserves_N, a_min, settings);
}

// What the plan minimized: the nonlinear effort's value, or the map's linear cost.
double minimized(const OpenLoopOptions& o, const OpenLoopPlan& plan) {
  return o.sos.effort ? plan.sos.effort_value : plan.sos.cost_N_s;
}

// The plan along the optimized path, started from the path stage's plan and points (it is
// certified there like any plan along a path). Its torque model is refined while that plan fails
// or costs clearly more than the path stage's (FreePathStudyOptions::max_torque_refinements); the
// best plan made is kept, with `plan`'s report.
void refine_along_optimized_path(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const FlatOutputBoundary& bc,
                                 const OpenLoopOptions& o, const OpenLoopStudyOptions& study, const FreePathOutcome& free,
                                 OpenLoopPlan& plan) {
  const BoundsWarmStart warm{free.theta, free.times_s};
  const FreePathStudyOptions& f = study.free_path;
  FreePathReport& report = plan.free_path;
  OpenLoopOptions along = o;
  OpenLoopPlan best;
  int best_pieces = 0;
  for (int refinement = 0;; ++refinement) {
    OpenLoopPlan attempt = plan;
    attempt.path = free.path;
    attempt.Y.reset();
    attempt.check = PlanCheck{};
    plan_along_path(flat, workspace, bc, along, study, attempt, &warm);
    report.final_plans = refinement + 1;
    // A solved plan beats a failed one and a cheaper one a dearer one; among failures the last
    // (finest torque model) says why.
    const bool solved = attempt.status == SolveStatus::Solved, best_solved = best.status == SolveStatus::Solved;
    if ((solved && (!best_solved || minimized(o, attempt) < minimized(o, best))) || (!solved && !best_solved)) {
      best = std::move(attempt);
      best_pieces = along.torque.pieces;
    }
    const bool close = best.status == SolveStatus::Solved &&
                       minimized(o, best) <= (1.0 + f.torque_model_relative_gap) * free.cost_N_s;
    if (close || refinement == f.max_torque_refinements) break;
    along.torque.pieces *= 2;
    along.torque.piece_growth = std::sqrt(along.torque.piece_growth);
  }
  report.final_torque_pieces = best_pieces;
  report.optimized = true;
  const FreePathReport kept = report;
  plan = std::move(best);
  plan.free_path = kept;
  if (plan.status != SolveStatus::Solved && kept.final_plans > 1)
    plan.message += " (along the optimized path with torque models of " + std::to_string(o.torque.pieces) + " to " +
                    std::to_string(along.torque.pieces) + " pieces)";
}

}  // namespace

void plan_along_free_path(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const FlatOutputBoundary& bc,
                          const Eigen::MatrixXd& initial_q_jet, const OpenLoopOptions& o,
                          const OpenLoopStudyOptions& study, int start_spans, OpenLoopPlan& plan) {
  const Stopwatch wall;
  FreePathReport& report = plan.free_path;
  report.prescribed_status = to_string(plan.status);
  report.prescribed_cost_N_s = plan.status == SolveStatus::Solved ? minimized(o, plan) : 0.0;
  report.start_flat_output_spans = start_spans;
  // From the prescribed path's plan, or, when the bounds cannot be met along it, from its closest.
  if (!plan.sos.Y) return;  // nothing to start from: the prescribed plan's status says why
  const SosSetup program =
      set_up_sos_program(flat, plan.torque, o.duration_s, bc, o.reserves_N, sos_settings(o.sos, study.sos));
  const FreePathOutcome free = optimize_path(flat, initial_q_jet, o, study, start_spans, plan, program);
  report.method = study.free_path.method;
  report.cost_at_points_N_s = free.cost_N_s;
  report.rounds = free.rounds;
  report.points = free.points;
  report.path_iterations = free.path_iterations;
  report.evaluations = free.evaluations;
  report.sequential_lp_iterations = report.slp_iterations = free.sequential_lp_iterations;
  if (!free.converged) {
    report.seconds = wall.seconds();
    plan.status = free.infeasible ? SolveStatus::Infeasible : SolveStatus::Failed;
    plan.message = "the joint path was not optimized: " + free.failure + " (the prescribed path's plan: " +
                   report.prescribed_status + ")";
    plan.Y.reset();
    return;
  }
  refine_along_optimized_path(flat, workspace, bc, o, study, free, plan);
  plan.free_path.seconds = wall.seconds();
}

}  // namespace detail
}  // namespace flatsos::planner
