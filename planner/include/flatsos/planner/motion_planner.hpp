#pragma once
// The planner API for a model built with the plugin: plan an open-loop transfer between a
// muscle state and a rest target (PMPP + torque model + SOS program + dense a-posteriori check),
// or one receding-horizon step (cubic path + torque box + SLP).

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
#include "flatsos/planner/plan_excitations.hpp"
#include "flatsos/planner/slp.hpp"
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
  /// The flatness planner takes efforts linear in the tendon forces (FlatOutputMap::withEffort).
  std::shared_ptr<const Effort> effort;
  /// The flat outputs' basis and the bounds. By default quintic B-splines on uniform spans whose
  /// number S = 0 is chosen from the model (automatic_flat_output_spans).
  SosProgramOptions sos = [] {
    SosProgramOptions s;
    s.flat_output_degree = 5;
    s.flat_output_spans = 0;
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
/// `options` with an automatic basis (flat_output_spans 0, torque pieces 0) made explicit for
/// `flat`; what plan_open_loop plans with.
OpenLoopOptions resolve_basis(const FlatOutputMap& flat, OpenLoopOptions options);

struct OpenLoopPlan {
  SolveStatus status = SolveStatus::Failed;
  std::string message;
  /// Implausible inputs that were accepted (joint angles beyond one turn: degrees as radians?).
  std::vector<std::string> warnings;
  JointPath path;                     ///< degree-8 joint polynomials, or the optimized spline (free path)
  std::optional<SplineTrajectory> Y;  ///< flat outputs (N); none unless the SOS program was solved
  int flat_output_degree = 0, flat_output_spans = 0;  ///< the basis planned in (resolve_basis)
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

/// Bounds on what an RH step's plan asks of the muscles over its first control period (what the
/// controller applies): 0 <= n <= 1 and floor <= a <= 1 at `samples` uniform times in
/// [0, period_s]. The RH controller sets period_s and samples to its own control period and
/// excitation samples, so it never has an excitation to clamp.
struct PeriodExcitationBounds {
  bool enforce = true;
  double period_s = 0.05;
  int samples = 11;
};

struct RecedingHorizonOptions {
  double horizon_s = 0.5;
  int grid_points = 11;               ///< torque box sampled here (the paper's grid)
  Eigen::VectorXd target_q_rad;
  Eigen::VectorXd reserves_N;
  SlpSolver solver = SlpSolver::VertexEnumeration;
  /// Joint torque the muscles need not produce (N m per joint; empty: none): the planned
  /// muscle torques are ID(path) - offset. The RH controller's disturbance observer sets it.
  Eigen::VectorXd torque_offset_N_m;
  PeriodExcitationBounds excitation_bounds;
};

struct RecedingHorizonStep {
  SolveStatus status = SolveStatus::Failed;
  std::string message;
  JointPath path;                     ///< cubic from (q, qd) to (target, 0) over the horizon
  Eigen::VectorXd tau_min, tau_max;   ///< torque box over the horizon grid
  /// The SLP's rows G alpha >= B. Constant moment arms: G = C_Y and B = slp_bound_vector of the
  /// box and reserves (m rows). Posture-dependent ones: at each grid posture q_i,
  /// C_Y(q_i) alpha >= reserves - C_tau(q_i) tau_i (grid_points x m rows, exact at the grid).
  Eigen::MatrixXd reserve_rows;
  Eigen::VectorXd bound_N;
  SlpResult slp;                      ///< alpha and its cost (moved inside the bounds when they were imposed)
  Eigen::VectorXd torque_offset_N_m;  ///< the options' offset the step was planned with (may be empty)
  /// The SLP's optimum left the excitation bounds on the first period and the bounds' sequential
  /// LP moved alpha inside (cost raised); its LP steps.
  bool bounds_imposed = false;
  int bound_iterations = 0;
  int bound_lp_pivots = 0;  ///< the simplex pivots of those LP steps
  /// buffers.excitations hold this step's excitations (alpha, path, offset as returned) on the
  /// bounds' samples of the first period, so a controller need not compute them again. Set by
  /// plan_receding_horizon_step; a planner that changes the step afterwards must clear it.
  bool first_period_sampled = false;
  const Eigen::VectorXd& alpha() const { return slp.alpha; }  ///< constant Y, N
  /// The excitations the plan asks for at `count` times tau0 + i h (s from the step's start;
  /// after the horizon the target is held at rest): count x m, what the RH controller applies
  /// (the inverse map with Y = alpha and the torque offset). Throws std::logic_error for a step
  /// that was not solved, std::runtime_error where they are not finite, std::invalid_argument
  /// for count < 1, h <= 0 or tau0 < 0.
  Eigen::MatrixXd excitations(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, double tau0_s, double h_s,
                              int count) const;
  double wall_seconds = 0.0;
  /// Where the step's time went: the horizon's grid (joint path, inverse dynamics, the SLP's
  /// rows), the SLP (slp.wall_seconds) and the excitation bounds (sampling the first period
  /// and, when they bind, their sequential LP).
  double grid_seconds = 0.0, bounds_seconds = 0.0;
  /// Work storage the in-place plan_receding_horizon_step reuses (not part of the result).
  struct Buffers {
    Jet joint_jet;
    Eigen::VectorXd torque_N_m;
    SlpWorkspace slp;
    PlanExcitationScratch period;                  ///< the first period's samples
    Eigen::MatrixXd excitations, activations;      ///< there: samples x m
    /// The last alpha the bounds' sequential LP converged to: the next bounded step of a
    /// receding horizon may start there.
    Eigen::VectorXd bounded_alpha;
    /// ... and its sequential LP's last basis, where the next one restarts (the rows keep their
    /// identity from period to period: sample, muscle, bound).
    SlpBasis bounds_basis;
  } buffers;
};

/// Checks RH options against the model: horizon > 0 s, >= 2 grid points, target and reserves
/// (>= 0 N) of the model's sizes and finite, a torque offset (if any) of one entry per joint,
/// enforced excitation bounds on a period in (0, horizon] with >= 2 samples. Throws
/// std::invalid_argument naming the field.
void validate(const RecedingHorizonOptions& options, const FlatOutputMap& flat);

/// One RH step from the measured joint state (the SLP formulation: no initial constraints on Y,
/// terminal equilibrium), with the excitation bounds on its first period (options.
/// excitation_bounds): Infeasible when no constant alpha meets them (the message names the
/// muscle and time). Throws std::invalid_argument for bad options (see validate) or a
/// joint state of the wrong size or not finite.
RecedingHorizonStep plan_receding_horizon_step(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                               const Eigen::VectorXd& q_rad, const Eigen::VectorXd& qd_rad_per_s,
                                               const RecedingHorizonOptions& options);
/// The same into `step`, reusing its storage: with SlpSolver::VertexEnumeration and a step that
/// has planned for this model before, nothing is allocated (the receding-horizon controller's
/// inner loop) unless the bounds must move alpha (their sequential LP allocates, as does Clp).
void plan_receding_horizon_step(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                const Eigen::VectorXd& q_rad, const Eigen::VectorXd& qd_rad_per_s,
                                const RecedingHorizonOptions& options, RecedingHorizonStep& step);
/// The same with a temporary workspace.
RecedingHorizonStep plan_receding_horizon_step(const FlatOutputMap& flat, const Eigen::VectorXd& q_rad,
                                               const Eigen::VectorXd& qd_rad_per_s, const RecedingHorizonOptions& options);

}  // namespace flatsos::planner
