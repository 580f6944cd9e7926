#include "flatsos/planner/open_loop.hpp"
#include "flatsos/planner/open_loop_study.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "flatness/input_checks.hpp"
#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/plugin/model/plausibility.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "open_loop/plan_along_path.hpp"
#include "path/free_path_stage.hpp"

namespace flatsos::planner {

Preset preset_named(const std::string& name) {
  for (const Preset p : {Preset::Best, Preset::Paper})
    if (name == to_string(p)) return p;
  throw std::invalid_argument("preset '" + name + "': expected 'best' or 'paper'");
}

int automatic_flat_output_spans(int flat_outputs, int degree) {
  constexpr int kCoefficients = 212, kMostSpans = 48;
  return std::clamp(kCoefficients / std::max(flat_outputs, 1) - degree, 1, kMostSpans);
}

double automatic_span_growth(const Effort* effort) {
  constexpr double kNonlinearEffortGrowth = 1.06;
  return effort && !effort->tendonForceWeights() ? kNonlinearEffortGrowth : 1.0;
}

OpenLoopOptions resolve_basis(const FlatOutputMap& flat, OpenLoopOptions o) {
  if (o.sos.flat_output_spans == 0)
    o.sos.flat_output_spans = automatic_flat_output_spans(flat.numFlatOutputs(), o.sos.flat_output_degree);
  const bool automatic_growth = o.sos.flat_output_span_growth == 0.0;
  if (automatic_growth)
    o.sos.flat_output_span_growth = automatic_span_growth(o.sos.effort ? o.sos.effort.get() : o.effort.get());
  if (o.torque.pieces == 0) {
    o.torque.pieces = std::max(12, o.sos.flat_output_spans);
    if (automatic_growth && o.torque.pieces == o.sos.flat_output_spans)
      o.torque.piece_growth = o.sos.flat_output_span_growth;
  }
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

// One plan_open_loop call with resolved options: its steps share the inputs, the initial flat
// state and the boundary conditions.
class OpenLoopPlanning {
 public:
  OpenLoopPlanning(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const MuscleState& initial,
                   OpenLoopOptions options, const OpenLoopStudyOptions& study)
      : flat_(flat), workspace_(workspace), initial_(initial), o_(std::move(options)), study_(study) {}

  OpenLoopPlan plan() {
    const Stopwatch setup;
    validate();
    OpenLoopPlan plan = startPlan();
    if (!initialForcesMeetReserves(plan)) return plan;
    setBoundary(plan);
    const double before_sos = setup.seconds();
    const int start_spans = planAlongPrescribedPath(plan);
    plan.setup_seconds += before_sos;
    if (o_.free_path.enabled) detail::plan_along_free_path(flat_, workspace_, bc_, y0_.q, o_, study_, start_spans, plan);
    if (plan.status == SolveStatus::Solved)
      for (auto& w : detail::joint_range_warnings(flat_.model().description(), plan.path, o_.duration_s, o_.check_points))
        plan.warnings.push_back(std::move(w));
    return plan;
  }

 private:
  // Throws std::invalid_argument naming the field.
  void validate() {
    const int n = flat_.numJoints(), m = flat_.numMuscles();
    if (!(o_.duration_s > 0.0) || !std::isfinite(o_.duration_s))
      throw std::invalid_argument("open-loop plan: duration T must be > 0 s");
    detail::require(o_.target_q_rad, n, "target joint angles");
    detail::require_within_joint_ranges(flat_.model().description(), o_.target_q_rad, "target joint angles");
    detail::require_taut_tendons_possible(flat_.model(), o_.target_q_rad, "target joint angles");
    detail::require_reserves(o_.reserves_N, m);
    if (o_.check_points < 2) throw std::invalid_argument("open-loop plan: check_points must be >= 2");
    detail::validate_free_path_options(flat_, o_, study_);
    detail::require_initial_muscle_state(flat_, initial_);
    y0_ = flat_.forward(workspace_, initial_);  // validates q, qd sizes too
    detail::require_within_joint_ranges(flat_.model().description(), initial_.q_rad, "initial joint angles");
  }

  OpenLoopPlan startPlan() const {
    OpenLoopPlan plan;
    plan.flat_output_degree = o_.sos.flat_output_degree;
    plan.flat_output_spans = o_.sos.flat_output_spans;
    plan.flat_output_span_growth = o_.sos.flat_output_span_growth;
    const auto& description = flat_.model().description();
    plan.warnings = plugin::joint_angle_warnings(description, initial_.q_rad, "initial joint angles");
    for (auto& w : plugin::joint_angle_warnings(description, o_.target_q_rad, "target joint angles"))
      plan.warnings.push_back(std::move(w));
    return plan;
  }

  // The reserves hold at t = 0 too, where the initial state fixes every tendon force: below a
  // reserve there, no plan exists, whatever the torque model or the flat outputs' degree.
  bool initialForcesMeetReserves(OpenLoopPlan& plan) const {
    for (int j = 0; j < flat_.numMuscles(); ++j) {
      const auto& mp = flat_.model().muscle(j).getParameters();
      const double F0 = muscles::tendon_force(mp, initial_.tendon_length_m[j]);
      // To the SOS program's feasibility margin: a rest state on a vertex meets reserves to rounding.
      if (F0 >= o_.reserves_N[j] - study_.sos.feasibility_margin_N) continue;
      std::ostringstream why;
      why << "initial tendon force of '" << mp.name << "' is " << F0 << " N, below its reserve of " << o_.reserves_N[j]
          << " N: no plan from this state can meet it (lower the reserve or start from a state with more force)";
      plan.status = SolveStatus::Infeasible;
      plan.message = why.str();
      return false;
    }
    return true;
  }

  // The degree-8 joint path to rest at the target, and the flat outputs' boundary conditions:
  // Y, dY at t = 0 from the initial state, dY = ddY = 0 at T.
  void setBoundary(OpenLoopPlan& plan) {
    Eigen::MatrixXd terminal = Eigen::MatrixXd::Zero(flat_.numJoints(), 5);
    terminal.col(0) = o_.target_q_rad;
    plan.path = fit_joint_path(o_.duration_s, y0_.q, terminal);
    bc_.initial = y0_.Y;
    bc_.terminal = Eigen::MatrixXd::Zero(flat_.numFlatOutputs(), 2);
    bc_.terminal_first_order = 1;
  }

  // The plan along the prescribed path; returns the spans of its basis. With a free path it only
  // starts the path stage: a coarser nested basis gives it for a fraction of the time
  // (FreePathStudyOptions::start_min_spans), and it needs no certificates (the plan along the
  // optimized path gets its own).
  int planAlongPrescribedPath(OpenLoopPlan& plan) {
    const int spans = o_.sos.flat_output_spans;
    OpenLoopOptions start = o_;
    OpenLoopStudyOptions start_study = study_;
    if (o_.free_path.enabled) {
      start_study.sos.certify = false;
      const int fewest = static_cast<int>(bc_.initial.cols() + bc_.terminal.cols()) - o_.sos.flat_output_degree + 1;
      start.sos.flat_output_spans =
          detail::start_flat_output_spans(spans, study_.free_path.start_min_spans, fewest);
      start.sos.flat_output_span_growth = std::pow(o_.sos.flat_output_span_growth, spans / start.sos.flat_output_spans);
    }
    detail::plan_along_path(flat_, workspace_, bc_, start, start_study, plan);
    if (start.sos.flat_output_spans != spans && plan.status != SolveStatus::Solved) {
      start.sos.flat_output_spans = spans;  // no plan in the coarse basis: the flat outputs' own
      start.sos.flat_output_span_growth = o_.sos.flat_output_span_growth;
      detail::plan_along_path(flat_, workspace_, bc_, start, start_study, plan);
    }
    return start.sos.flat_output_spans;
  }

  const FlatOutputMap& flat_;
  plugin::ModelWorkspace& workspace_;
  const MuscleState& initial_;
  const OpenLoopOptions o_;
  const OpenLoopStudyOptions& study_;
  FlatState y0_;
  FlatOutputBoundary bc_;
};

// The plan in the resolved basis. The graded spans a nonlinear effort gets by default resolve its
// optimum's first tenths of a second, but on some models (arm26's muscles) their short first spans
// leave the bounded exchange without a plan where uniform spans find one: there, uniform spans.
OpenLoopPlan plan_in_automatic_basis(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                     const MuscleState& initial, const OpenLoopOptions& options,
                                     const OpenLoopStudyOptions& study) {
  const OpenLoopOptions resolved = resolve_basis(flat, options);
  OpenLoopPlan graded = OpenLoopPlanning(flat, workspace, initial, resolved, study).plan();
  const bool automatic_grading = options.sos.flat_output_span_growth == 0.0 &&
                                 resolved.sos.flat_output_span_growth != 1.0 && resolved.sos.flat_output_spans > 1;
  if (graded.status == SolveStatus::Solved || !automatic_grading) return graded;
  OpenLoopOptions uniform = options;
  uniform.sos.flat_output_span_growth = 1.0;
  OpenLoopPlan plan = OpenLoopPlanning(flat, workspace, initial, resolve_basis(flat, uniform), study).plan();
  if (plan.status != SolveStatus::Solved) return graded;
  std::ostringstream why;
  why << "no plan on the default spans growing by " << resolved.sos.flat_output_span_growth << " (" << graded.message
      << "): planned again on uniform spans";
  plan.warnings.push_back(why.str());
  plan.setup_seconds += graded.setup_seconds;  // the graded attempt's time counts too
  plan.solve_seconds += graded.solve_seconds + graded.certify_seconds + graded.check_seconds;
  return plan;
}

}  // namespace

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
  if (options.effort) {
    options.effort->validate(flat.numMuscles());
    OpenLoopOptions rest = options;
    rest.effort = nullptr;
    // A linear effort: the same plan on a map that minimizes it. A nonlinear one: the SOS
    // program minimizes it from the optimum of the map's own linear effort (and the free path's
    // stage from the prescribed path's plan).
    if (options.effort->tendonForceWeights())
      return plan_open_loop(flat.withEffort(options.effort), workspace, initial, rest, study);
    rest.sos.effort = options.effort;
    return plan_in_automatic_basis(flat, workspace, initial, rest, study);
  }
  return plan_in_automatic_basis(flat, workspace, initial, options, study);
}

}  // namespace flatsos::planner
