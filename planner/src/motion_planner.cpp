#include "flatsos/planner/motion_planner.hpp"
#include "flatsos/planner/motion_planner_study.hpp"
#include "flatsos/planner/receding_horizon_study.hpp"
#include "flatsos/planner/slp_study.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <sstream>
#include <stdexcept>

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/planner/plan_excitations.hpp"
#include "flatsos/plugin/model/plausibility.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "input_checks.hpp"
#include "path/free_path.hpp"
#include "path/free_path_settings.hpp"
#include "period_bounds.hpp"
#include "sos/bound_rows.hpp"
#include "sos/sos_bounds.hpp"
#include "sos/sos_setup.hpp"

namespace flatsos::planner {

FreePathMethod free_path_method(const std::string& name) {
  for (const FreePathMethod m : {FreePathMethod::ReducedQuasiNewton, FreePathMethod::JointNewton})
    if (name == to_string(m)) return m;
  throw std::invalid_argument("free path method '" + name + "': expected 'reduced_quasi_newton' or 'joint_newton'");
}

Preset preset_named(const std::string& name) {
  for (const Preset p : {Preset::Best, Preset::Paper})
    if (name == to_string(p)) return p;
  throw std::invalid_argument("preset '" + name + "': expected 'best' or 'paper'");
}

int automatic_flat_output_spans(int flat_outputs, int degree) {
  constexpr int kCoefficients = 212, kMostSpans = 48;
  return std::clamp(kCoefficients / std::max(flat_outputs, 1) - degree, 1, kMostSpans);
}

OpenLoopOptions resolve_basis(const FlatOutputMap& flat, OpenLoopOptions o) {
  if (o.sos.flat_output_spans == 0)
    o.sos.flat_output_spans = automatic_flat_output_spans(flat.numFlatOutputs(), o.sos.flat_output_degree);
  if (o.torque.pieces == 0) o.torque.pieces = std::max(12, o.sos.flat_output_spans);
  return o;
}

OpenLoopOptions open_loop_options(Preset preset) {
  OpenLoopOptions o;
  if (preset == Preset::Paper) {
    o.sos.flat_output_degree = 4;
    o.sos.flat_output_spans = 1;
    o.torque.pieces = 12;
  }
  return o;
}

namespace {

using detail::require;
using detail::require_reserves;

// A posture where some path is not longer than its tendon's slack length cannot be held with
// taut tendons, which flatness needs (typically: degrees given as radians). Allocates nothing
// when it passes.
void require_taut_tendons_possible(const plugin::MusculoskeletalModel& model, const Eigen::VectorXd& q, const char* what) {
  for (int j = 0; j < model.numMuscles(); ++j) {
    const double L = model.musculotendonLength(j, q);
    const auto& mp = model.muscle(j).getParameters();
    if (!(L > mp.tendon_slack_length_m)) {
      std::ostringstream why;
      why << what << ": the musculotendon path of '" << mp.name << "' would be " << L
          << " m long there, not longer than its tendon slack length " << mp.tendon_slack_length_m
          << " m, so its tendon cannot be taut (are the angles in radians?)";
      throw std::invalid_argument(why.str());
    }
  }
}

// The plan along plan.path (torque model, SOS program with the bounds, dense check): sets every
// field but the path, the warnings and the free-path report. `warm`: the bounded exchange's start.
void plan_along_path(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const FlatOutputBoundary& bc,
                     const OpenLoopOptions& o, const OpenLoopStudyOptions& study, OpenLoopPlan& plan,
                     const detail::BoundsWarmStart* warm = nullptr) {
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
  plan.sos = warm ? detail::solve_sos_program_from(flat, plan.torque, o.duration_s, bc, o.reserves_N,
                                                   detail::sos_settings(o.sos, study.sos), muscles, *warm)
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

void require_free_path_options(const FlatOutputMap& flat, const OpenLoopOptions& o, const OpenLoopStudyOptions& study) {
  if (!o.free_path.enabled) return;
  const detail::FreePathSettings f(o.free_path, study.free_path);
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
  if (f.max_rounds < 1 || f.max_path_iterations < 1 || f.max_slp_iterations < 1)
    throw std::invalid_argument("open-loop plan: free_path.max_rounds, max_path_iterations and max_slp_iterations must be >= 1");
  if (f.max_torque_refinements < 0 || f.max_torque_refinements > 10)
    throw std::invalid_argument("open-loop plan: free_path.max_torque_refinements must be in [0, 10] (each doubles "
                                "the torque pieces)");
  if (!(f.torque_model_relative_gap >= 0.0) || !std::isfinite(f.torque_model_relative_gap))
    throw std::invalid_argument("open-loop plan: free_path.torque_model_relative_gap must be finite and >= 0");
}

// The flat outputs' spans of the plan that starts the path stage: S / f for the largest divisor
// f of S that leaves at least `min_spans` (S / f spans growing by growth^f have every f-th
// breakpoint of the S spans, so their splines are among the S spans').
// `fewest`: the spans that leave the flat outputs a free coefficient besides their boundary
// conditions.
int start_spans(int spans, int min_spans, int fewest) {
  if (min_spans == 0) return spans;
  for (int f = spans; f > 1; --f)
    if (spans % f == 0 && spans / f >= std::max(min_spans, fewest)) return spans / f;
  return spans;
}

}  // namespace

Jet OpenLoopPlan::flatOutputJet(double t) const {
  if (!Y) throw std::logic_error("open-loop plan: no flat outputs (" + message + ")");
  return Y->jet(t, 3);
}

Eigen::MatrixXd RecedingHorizonStep::excitations(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                                 double tau0_s, double h_s, int count) const {
  if (status != SolveStatus::Solved) throw std::logic_error("RH step: no excitations: the step was not solved (" + message + ")");
  if (count < 1 || !(h_s > 0.0) || !(tau0_s >= 0.0)) throw std::invalid_argument("RH step excitations: need count >= 1, h > 0 s, tau0 >= 0 s");
  PlanExcitationScratch scratch;
  Eigen::MatrixXd out;
  if (!sample_plan_excitations(flat, workspace, path, alpha(), torque_offset_N_m, tau0_s, h_s, count, scratch, out))
    throw std::runtime_error("RH step excitations: not finite (the plan leaves the model's valid domain)");
  return out;
}

PlanCheck check_plan(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const JointPath& path,
                     const SplineTrajectory& Y, const Eigen::VectorXd& reserves, int points, double bound_tolerance) {
  if (points < 2) throw std::invalid_argument("plan check: need at least 2 points");
  PlanCheck c;
  c.points = points;
  c.min_tendon_force_N = c.min_reserve_margin_N = c.min_activation = c.min_excitation = 1e300;
  c.max_activation = c.max_excitation = -1e300;
  const double h = path.duration_s / (points - 1);
  const std::vector<TorqueJet> jets = torque_jets_on_grid(flat, workspace, path, h, points);
  DomainViolation limiting;           // the most fundamental kind, then the largest excess
  std::size_t limiting_muscle = 0;
  std::map<std::pair<std::size_t, DomainViolation::Kind>, double> first_time;  // per muscle and kind
  Jet q_jet(flat.numJoints(), 5), y_jet(flat.numFlatOutputs(), 3);
  MusclePoint mp;
  for (int i = 0; i < points; ++i) {
    const double t = h * i;
    path.jetInto(t, q_jet);
    Y.jetInto(t, y_jet);
    flat.inverseFromTorque(q_jet, jets[static_cast<std::size_t>(i)], y_jet, mp);
    c.min_tendon_force_N = std::min(c.min_tendon_force_N, mp.tendon_force_N.minCoeff());
    c.min_reserve_margin_N = std::min(c.min_reserve_margin_N, (mp.tendon_force_N - reserves).minCoeff());
    if (mp.activation.allFinite()) {
      c.min_activation = std::min(c.min_activation, mp.activation.minCoeff());
      c.max_activation = std::max(c.max_activation, mp.activation.maxCoeff());
    }
    if (mp.excitation.allFinite()) {
      c.min_excitation = std::min(c.min_excitation, mp.excitation.minCoeff());
      c.max_excitation = std::max(c.max_excitation, mp.excitation.maxCoeff());
    }
    bool outside = false;
    for (std::size_t j = 0; j < mp.domain_violation.size(); ++j) {
      const DomainViolation& v = mp.domain_violation[j];
      if (!v.violated()) continue;
      const bool bound_kind = v.kind == DomainViolation::Kind::ActivationOutsideUnitInterval ||
                              v.kind == DomainViolation::Kind::ActivationBelowFloor ||
                              v.kind == DomainViolation::Kind::ExcitationOutsideUnitInterval;
      if (bound_kind && v.excess() <= bound_tolerance) continue;
      outside = true;
      if (c.first_violation.empty()) {
        std::ostringstream why;
        why << "t = " << t << " s, muscle '" << flat.model().description().muscles[j].parameters.name
            << "': " << v.describe();
        c.first_violation = why.str();
      }
      first_time.try_emplace({j, v.kind}, t);
      if (!limiting.violated() || v.kind < limiting.kind || (v.kind == limiting.kind && v.excess() > limiting.excess())) {
        limiting = v;
        limiting_muscle = j;
      }
    }
    if (outside) ++c.points_outside_domain;
  }
  if (limiting.violated()) {
    std::ostringstream why;
    why << "muscle '" << flat.model().description().muscles[limiting_muscle].parameters.name
        << "': " << limiting.describe() << " (worst), from t = " << first_time.at({limiting_muscle, limiting.kind}) << " s";
    c.limiting_violation = why.str();
  }
  return c;
}

OpenLoopPlan plan_open_loop(const FlatOutputMap& flat, const MuscleState& initial, const OpenLoopOptions& o) {
  return plan_open_loop(flat, initial, o, OpenLoopStudyOptions{});
}

OpenLoopPlan plan_open_loop(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const MuscleState& initial,
                            const OpenLoopOptions& o) {
  return plan_open_loop(flat, workspace, initial, o, OpenLoopStudyOptions{});
}

OpenLoopPlan plan_open_loop(const FlatOutputMap& flat, const MuscleState& initial, const OpenLoopOptions& o,
                            const OpenLoopStudyOptions& study) {
  plugin::ModelWorkspace workspace = flat.makeWorkspace();
  return plan_open_loop(flat, workspace, initial, o, study);
}

OpenLoopPlan plan_open_loop(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const MuscleState& initial,
                            const OpenLoopOptions& options, const OpenLoopStudyOptions& study) {
  if (options.effort) {  // the same plan on a map that minimizes this effort
    OpenLoopOptions rest = options;
    rest.effort = nullptr;
    return plan_open_loop(flat.withEffort(options.effort), workspace, initial, rest, study);
  }
  const Stopwatch setup;
  const OpenLoopOptions o = resolve_basis(flat, options);
  const int n = flat.numJoints(), m = flat.numMuscles(), p = flat.numFlatOutputs();
  if (!(o.duration_s > 0.0) || !std::isfinite(o.duration_s)) throw std::invalid_argument("open-loop plan: duration T must be > 0 s");
  require(o.target_q_rad, n, "target joint angles");
  require_taut_tendons_possible(flat.model(), o.target_q_rad, "target joint angles");
  require_reserves(o.reserves_N, m);
  if (o.check_points < 2) throw std::invalid_argument("open-loop plan: check_points must be >= 2");
  require_free_path_options(flat, o, study);
  detail::require_initial_muscle_state(flat, initial);
  const FlatState y0 = flat.forward(workspace, initial);  // validates q, qd sizes too

  OpenLoopPlan plan;
  plan.flat_output_degree = o.sos.flat_output_degree;
  plan.flat_output_spans = o.sos.flat_output_spans;
  plan.warnings = plugin::joint_angle_warnings(flat.model().description(), initial.q_rad, "initial joint angles");
  for (auto& w : plugin::joint_angle_warnings(flat.model().description(), o.target_q_rad, "target joint angles"))
    plan.warnings.push_back(std::move(w));
  // The reserves hold at t = 0 too, where the initial state fixes every tendon force: below a
  // reserve there, no plan exists, whatever the torque model or the flat outputs' degree.
  for (int j = 0; j < m; ++j) {
    const auto& mp = flat.model().muscle(j).getParameters();
    const double F0 = muscles::tendon_force(mp, initial.tendon_length_m[j]);
    // To the SOS program's feasibility margin: a rest state on a vertex meets reserves to rounding.
    if (F0 < o.reserves_N[j] - study.sos.feasibility_margin_N) {
      std::ostringstream why;
      why << "initial tendon force of '" << mp.name << "' is " << F0 << " N, below its reserve of " << o.reserves_N[j]
          << " N: no plan from this state can meet it (lower the reserve or start from a state with more force)";
      plan.status = SolveStatus::Infeasible;
      plan.message = why.str();
      return plan;
    }
  }
  Eigen::MatrixXd terminal = Eigen::MatrixXd::Zero(n, 5);
  terminal.col(0) = o.target_q_rad;
  plan.path = fit_joint_path(o.duration_s, y0.q, terminal);
  FlatOutputBoundary bc;
  bc.initial = y0.Y;                          // Y(0), dY(0)
  bc.terminal = Eigen::MatrixXd::Zero(p, 2);  // dY(T) = ddY(T) = 0
  bc.terminal_first_order = 1;
  const double before_sos = setup.seconds();
  // With a free path the prescribed path's plan only starts the path stage: a coarser nested
  // basis gives it for a fraction of the time (FreeJointPathOptions::start_min_spans), and it
  // needs no certificates (the plan along the optimized path gets its own; on the arm they were
  // 10 of the start's 70 ms).
  const int spans = o.sos.flat_output_spans;
  OpenLoopOptions start = o;
  OpenLoopStudyOptions start_study = study;
  if (o.free_path.enabled) {
    start_study.sos.certify = false;
    const int fewest = static_cast<int>(bc.initial.cols() + bc.terminal.cols()) - o.sos.flat_output_degree + 1;
    start.sos.flat_output_spans = start_spans(spans, study.free_path.start_min_spans, fewest);
    start.sos.flat_output_span_growth = std::pow(o.sos.flat_output_span_growth, spans / start.sos.flat_output_spans);
  }
  plan_along_path(flat, workspace, bc, start, start_study, plan);
  if (start.sos.flat_output_spans != spans && plan.status != SolveStatus::Solved) {
    start.sos.flat_output_spans = spans;  // no plan in the coarse basis: the flat outputs' own
    start.sos.flat_output_span_growth = o.sos.flat_output_span_growth;
    plan_along_path(flat, workspace, bc, start, start_study, plan);
  }
  plan.setup_seconds += before_sos;
  if (!o.free_path.enabled) return plan;

  // The joint path as a variable too, from the prescribed path's plan (or, when the bounds cannot
  // be met along it, from its closest plan), carried into the flat outputs' basis.
  const Stopwatch free_path;
  plan.free_path.prescribed_status = to_string(plan.status);
  plan.free_path.prescribed_cost_N_s = plan.status == SolveStatus::Solved ? plan.sos.cost_N_s : 0.0;
  plan.free_path.start_flat_output_spans = start.sos.flat_output_spans;
  if (!plan.sos.Y) return plan;  // nothing to start from: the prescribed plan's status says why
  const detail::SosSetup program =
      detail::set_up_sos_program(flat, plan.torque, o.duration_s, bc, o.reserves_N, detail::sos_settings(o.sos, study.sos));
  const Eigen::VectorXd a_min = detail::activation_minima(flat, o.sos.bounds);
  const SplineTrajectory start_Y = start.sos.flat_output_spans == spans ? *plan.sos.Y : plan.sos.Y->inBasis(program.basis);
  const detail::FreePathOutcome free = detail::optimize_joint_path(
      program, flat, plan.path, y0.q, o.target_q_rad, detail::theta_of(program, start_Y), o.reserves_N, a_min,
      detail::FreePathSettings(o.free_path, study.free_path));
  FreePathReport& report = plan.free_path;
  report.method = study.free_path.method;
  report.cost_at_points_N_s = free.cost_N_s;
  report.rounds = free.rounds;
  report.points = free.points;
  report.path_iterations = free.path_iterations;
  report.evaluations = free.evaluations;
  report.slp_iterations = free.slp_iterations;
  if (!free.converged) {
    report.seconds = free_path.seconds();
    plan.status = free.infeasible ? SolveStatus::Infeasible : SolveStatus::Failed;
    plan.message = "the joint path was not optimized: " + free.failure + " (the prescribed path's plan: " +
                   report.prescribed_status + ")";
    plan.Y.reset();
    return plan;
  }
  // The path stage's plan and points are where the bounded exchange along the new path starts
  // (it is certified there like any plan along a path). Its torque model is refined while that
  // plan fails or costs clearly more than the path stage's (FreeJointPathOptions::
  // max_torque_refinements); the best plan made is kept.
  const detail::BoundsWarmStart warm{free.theta, free.times_s};
  const FreePathStudyOptions& f = study.free_path;
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
    if ((solved && (!best_solved || attempt.sos.cost_N_s < best.sos.cost_N_s)) || (!solved && !best_solved)) {
      best = std::move(attempt);
      best_pieces = along.torque.pieces;
    }
    const bool close = best.status == SolveStatus::Solved &&
                       best.sos.cost_N_s <= (1.0 + f.torque_model_relative_gap) * free.cost_N_s;
    if (close || refinement == f.max_torque_refinements) break;
    along.torque.pieces *= 2;
    along.torque.piece_growth = std::sqrt(along.torque.piece_growth);
  }
  report.final_torque_pieces = best_pieces;
  report.optimized = true;
  report.seconds = free_path.seconds();
  const FreePathReport kept = report;
  plan = std::move(best);
  plan.free_path = kept;
  if (plan.status != SolveStatus::Solved && kept.final_plans > 1)
    plan.message += " (along the optimized path with torque models of " + std::to_string(o.torque.pieces) + " to " +
                    std::to_string(along.torque.pieces) + " pieces)";
  return plan;
}

void validate(const RecedingHorizonOptions& o, const FlatOutputMap& flat) {
  const int n = flat.numJoints();
  if (!(o.horizon_s > 0.0) || !std::isfinite(o.horizon_s)) throw std::invalid_argument("RH step: horizon must be > 0 s");
  if (o.grid_points < 2) throw std::invalid_argument("RH step: need at least 2 grid points");
  require(o.target_q_rad, n, "target joint angles");
  require_taut_tendons_possible(flat.model(), o.target_q_rad, "target joint angles");
  require_reserves(o.reserves_N, flat.numMuscles());
  if (o.torque_offset_N_m.size() > 0) require(o.torque_offset_N_m, n, "torque offset");
  const PeriodExcitationBounds& b = o.excitation_bounds;
  if (b.enforce) {
    if (!(b.period_s > 0.0 && b.period_s <= o.horizon_s))
      throw std::invalid_argument("RH step: excitation_bounds.period_s must be in (0, horizon]");
    if (b.samples < 2) throw std::invalid_argument("RH step: excitation_bounds.samples must be >= 2");
  }
}

RecedingHorizonStep plan_receding_horizon_step(const FlatOutputMap& flat, const Eigen::VectorXd& q,
                                               const Eigen::VectorXd& qd, const RecedingHorizonOptions& o) {
  return plan_receding_horizon_step(flat, q, qd, o, RecedingHorizonStudyOptions{});
}

RecedingHorizonStep plan_receding_horizon_step(const FlatOutputMap& flat, const Eigen::VectorXd& q,
                                               const Eigen::VectorXd& qd, const RecedingHorizonOptions& o,
                                               const RecedingHorizonStudyOptions& study) {
  plugin::ModelWorkspace workspace = flat.makeWorkspace();
  RecedingHorizonStep step;
  plan_receding_horizon_step(flat, workspace, q, qd, o, study, step);
  return step;
}

RecedingHorizonStep plan_receding_horizon_step(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                               const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                               const RecedingHorizonOptions& o) {
  RecedingHorizonStep step;
  plan_receding_horizon_step(flat, workspace, q, qd, o, step);
  return step;
}

void plan_receding_horizon_step(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const Eigen::VectorXd& q,
                                const Eigen::VectorXd& qd, const RecedingHorizonOptions& o, RecedingHorizonStep& step) {
  static const RecedingHorizonStudyOptions kProduct;  // constant: no allocation per step
  plan_receding_horizon_step(flat, workspace, q, qd, o, kProduct, step);
}

void plan_receding_horizon_step(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const Eigen::VectorXd& q,
                                const Eigen::VectorXd& qd, const RecedingHorizonOptions& o,
                                const RecedingHorizonStudyOptions& study, RecedingHorizonStep& step) {
  const Stopwatch wall;
  const int n = flat.numJoints();
  validate(o, flat);
  if (study.warm_start) require(*study.warm_start, flat.numFlatOutputs(), "SLP warm start");
  if (study.bound_max_iterations < 1) throw std::invalid_argument("RH step: bound_max_iterations must be >= 1");
  require(q, n, "joint angles");
  require(qd, n, "joint speeds");

  step.status = SolveStatus::Failed;
  step.message.clear();
  step.first_period_sampled = false;
  step.grid_seconds = step.bounds_seconds = 0.0;
  fit_rest_cubic(o.horizon_s, q, qd, o.target_q_rad, step.path);
  step.torque_offset_N_m = o.torque_offset_N_m;  // same size every period: no allocation
  const bool offset = o.torque_offset_N_m.size() > 0;
  step.buffers.joint_jet.resize(n, 3);
  step.buffers.torque_N_m.resize(n);
  step.tau_min.setConstant(n, 1e300);
  step.tau_max.setConstant(n, -1e300);
  const bool varying = !flat.hasConstantMomentArms();
  const int m = flat.numMuscles();
  // The paper's cost (sum of the flat outputs) is the SLP's default; other effort weights give
  // the cost c = C_Y^T w of the constant flat outputs.
  const bool flat_output_sum = flat.effortIsFlatOutputSum();
  if (flat_output_sum) step.buffers.slp.cost.resize(0);
  else step.buffers.slp.cost.setZero(flat.numFlatOutputs());
  if (varying) {
    step.reserve_rows.resize(o.grid_points * m, flat.numFlatOutputs());
    step.bound_N.resize(o.grid_points * m);
  }
  for (int i = 0; i < o.grid_points; ++i) {
    Jet& j = step.buffers.joint_jet;
    Eigen::VectorXd& tau = step.buffers.torque_N_m;
    const double t = o.horizon_s * i / (o.grid_points - 1);
    step.path.jetInto(t, j);
    flat.model().inverseDynamics(workspace, j.col(0), j.col(1), j.col(2), tau);
    if (offset) tau -= o.torque_offset_N_m;
    step.tau_min = step.tau_min.cwiseMin(tau);
    step.tau_max = step.tau_max.cwiseMax(tau);
    if (!varying) continue;
    // C(q) along the cubic: Assumption 1 at each grid posture, then the rows exact there.
    const std::string failure = flat.assumption1FailureAt(j.col(0));
    if (!failure.empty()) {
      step.message = "the horizon's joint path leaves the postures where the flat outputs are valid, at t = " +
                     std::to_string(t) + " s " + failure;
      step.wall_seconds = wall.seconds();
      return;
    }
    const ForceJetMap map = flat.forceJetMap(j.leftCols(1));
    step.reserve_rows.middleRows(i * m, m) = map.CY;
    step.bound_N.segment(i * m, m) = o.reserves_N - map.Ctau * tau;
    // The effort's flat-output part, C_Y(q)^T w, averaged over the horizon's grid.
    if (!flat_output_sum) step.buffers.slp.cost.noalias() += map.CY.transpose() * flat.effortWeights() / o.grid_points;
  }
  if (!varying) {
    step.reserve_rows = flat.CY();  // no allocation once sized
    slp_bound_vector(flat.Ctau(), step.tau_min, step.tau_max, o.reserves_N, step.bound_N);
    if (!flat_output_sum) step.buffers.slp.cost.noalias() = flat.CY().transpose() * flat.effortWeights();
  }
  step.grid_seconds = wall.seconds();
  if (study.slp_by_ipopt) solve_slp_by_ipopt(step.reserve_rows, step.bound_N, study.warm_start, step.buffers.slp, step.slp);
  else solve_slp(step.reserve_rows, step.bound_N, o.solver, step.buffers.slp, step.slp);
  step.status = step.slp.status;
  step.message = step.slp.message;
  const double before_bounds = wall.seconds();
  detail::impose_period_bounds(flat, workspace, o, study.bound_max_iterations, step);
  step.wall_seconds = wall.seconds();
  step.bounds_seconds = step.wall_seconds - before_bounds;
}

}  // namespace flatsos::planner
