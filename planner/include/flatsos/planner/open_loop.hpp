#pragma once
// The open-loop planner: a transfer between a muscle state and a rest target (the degree-8 joint
// path or a free one, the torque model, the SOS program with the excitation bounds, certificates
// and a dense a-posteriori check). open_loop_study.hpp holds the stages' study settings.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "flatsos/planner/effort.hpp"
#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/free_path.hpp"
#include "flatsos/planner/joint_paths.hpp"
#include "flatsos/planner/sos_program.hpp"
#include "flatsos/planner/torque_model.hpp"

namespace flatsos::planner {


/// What a plan implies along a dense time grid, from the exact inverse map.
struct PlanCheck {
  int points = 0;
  double min_tendon_force_N = 0.0;
  double min_reserve_margin_N = 0.0;  ///< min over grid and muscles of F_j - reserve_j
  double min_activation = 0.0, max_activation = 0.0;
  double min_excitation = 0.0, max_excitation = 0.0;
  int points_outside_domain = 0;      ///< grid points where some muscle leaves the valid domain
  std::string first_violation;        ///< "t = ... s, muscle '...': why"
  /// The limiting violation: the most fundamental kind found (a slack tendon before a too-fast
  /// fibre, ..., activation before excitation), the muscle with the largest excess of that kind,
  /// its worst value and from when: "muscle 'biceps': activation 1.7 outside (0, 1] (worst), from
  /// t = 0.2 s". Empty when every point is inside the domain.
  std::string limiting_violation;
};

/// The open-loop options (OpenLoopOptions{} is Preset::Best): the task, the effort, the basis of
/// the flat outputs, the torque model's pieces, the excitation bounds and the free path.
/// motion_planner_study.hpp holds the stages' study settings.
struct OpenLoopOptions {
  double duration_s = 3.0;
  Eigen::VectorXd target_q_rad;       ///< rest target (qd = qdd = q''' = q'''' = 0 there)
  Eigen::VectorXd reserves_N;         ///< minimum tendon force per muscle
  /// What to minimize (effort.hpp): null means the model's effort_weights (FlatOutputMap::effort).
  /// A nonlinear effort (squared excitations, ...) is minimized from the optimum of the model's
  /// linear one by a sequential QP (SosProgramOptions::effort), along the prescribed path.
  std::shared_ptr<const Effort> effort;
  /// The flat outputs' basis and the bounds. By default quintic B-splines whose number of spans
  /// S = 0 is chosen from the model (automatic_flat_output_spans) and whose growth 0 from the
  /// effort (automatic_span_growth).
  SosProgramOptions sos = [] {
    SosProgramOptions s;
    s.flat_output_degree = 5;
    s.flat_output_spans = 0;
    s.flat_output_span_growth = 0.0;
    return s;
  }();
  /// K cubic pieces. K = 0 (the default): as many as the flat outputs' spans, at least 12.
  TorqueModelOptions torque = [] {
    TorqueModelOptions t;
    t.pieces = 0;
    return t;
  }();
  FreeJointPathOptions free_path;     ///< the joint path optimized too (off: the degree-8 path)
  int check_points = 301;             ///< dense grid of the a-posteriori check
};

/// Named configurations of the open-loop planner (docs/method/sos_program.md, "Presets").
enum class Preset {
  /// The default: quintic B-splines on as many spans as the model's size allows
  /// (automatic_flat_output_spans: 48 on the paper's arm), as many cubic torque pieces, the
  /// excitation bounds.
  Best,
  /// Richter & Warner's configuration: one quartic flat-output polynomial (12 cubic torque
  /// pieces): 958.32 N s on the paper's scenario.
  Paper,
};
/// "best" or "paper": the names the programs and Python use.
constexpr const char* to_string(Preset p) { return p == Preset::Paper ? "paper" : "best"; }
/// The preset of that name; std::invalid_argument naming the accepted ones otherwise.
Preset preset_named(const std::string& name);
/// The options of a preset (duration, target and reserves are left to the caller).
OpenLoopOptions open_loop_options(Preset preset);
/// The flat outputs' spans of the default basis: about 212 B-spline coefficients over all p flat
/// outputs, S = 212 / p - degree within [1, 48] (48 for the paper's arm, p = 4; 12 for a 13-muscle
/// knee; 1 for a 40-muscle leg). The plan's linear programs and bounds grow with the
/// coefficients times the muscles, and a richer basis costs less effort.
int automatic_flat_output_spans(int flat_outputs, int degree);
/// The spans' growth of the default basis: 1 (uniform) for an effort linear in the tendon
/// forces; 1.06 for a nonlinear one, whose optimum spends its effort in the first tenths of a
/// second of a transfer (the paper's arm, squared excitations, 48 spans: 1.4 % above the
/// collocation optimum with uniform spans, 0.15 % with 1.06).
double automatic_span_growth(const Effort* effort);
/// `options` with an automatic basis (flat_output_spans 0, span growth 0, torque pieces 0) made
/// explicit for `flat`; what plan_open_loop plans with. The torque pieces follow the spans'
/// growth when both are automatic.
OpenLoopOptions resolve_basis(const FlatOutputMap& flat, OpenLoopOptions options);

struct OpenLoopPlan {
  SolveStatus status = SolveStatus::Failed;
  std::string message;
  /// Implausible inputs that were accepted (joint angles beyond one turn: degrees as radians?).
  std::vector<std::string> warnings;
  JointPath path;                     ///< degree-8 joint polynomials, or the optimized spline (free path)
  std::optional<SplineTrajectory> Y;  ///< flat outputs (N); none unless the SOS program was solved
  int flat_output_degree = 0, flat_output_spans = 0;  ///< the basis planned in (resolve_basis)
  double flat_output_span_growth = 1.0;               ///< its spans' growth (1: uniform)
  SosProgramResult sos;
  TorqueModel torque;
  PlanCheck check;
  FreePathReport free_path;
  double setup_seconds = 0.0;         ///< forward map, joint paths, torque model, SOS setup
  double solve_seconds = 0.0;         ///< exchange LPs
  double certify_seconds = 0.0;
  double check_seconds = 0.0;

  Jet jointJet(double t) const { return path.jet(t, 5); }
  /// p x 3: Y, dY, ddY. Throws std::logic_error when the plan has no flat outputs.
  Jet flatOutputJet(double t) const;
};

/// Open-loop plan from `initial` to rest at options.target_q_rad in options.duration_s.
/// With the automatic graded basis of a nonlinear effort (span growth 0 resolved to 1.06), a plan
/// that fails there is planned again on uniform spans, and a warning says so.
/// The initial muscle state fixes q, qd, qdd, q''' and Y, dY at t = 0 (forward map); terminal
/// rest fixes qd..q'''' = 0 and dY = ddY = 0. Throws std::invalid_argument for bad input (sizes,
/// NaN, T <= 0, negative reserves, initial state outside the model's valid domain); solver
/// outcomes come back as statuses: Infeasible also when the SOS program is solved but the plan
/// leaves the model's valid domain on the check grid (activation above 1, excitation outside
/// [0, 1], ...), since the muscles cannot execute it.
OpenLoopPlan plan_open_loop(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const MuscleState& initial,
                            const OpenLoopOptions& options);
/// The same with a temporary workspace (a State copy, tens of microseconds).
OpenLoopPlan plan_open_loop(const FlatOutputMap& flat, const MuscleState& initial, const OpenLoopOptions& options);

/// The a-posteriori check of any flat trajectory on `points` uniform times in [0, T]. Activations
/// and excitations outside their bounds by at most `bound_tolerance` do not count as leaving the
/// domain (the bounded plans' tolerance; 0: exact).
PlanCheck check_plan(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const JointPath& path,
                     const SplineTrajectory& Y, const Eigen::VectorXd& reserves_N, int points,
                     double bound_tolerance = 0.0);

}  // namespace flatsos::planner
