#pragma once
// One receding-horizon step (the paper's "Linear Programming Solution"): a cubic joint path to
// rest at the target over the horizon, the torque box over its grid, the SLP for constant flat
// outputs, and the excitation bounds on the first control period. receding_horizon_study.hpp
// holds its study settings.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "flatsos/planner/effort.hpp"
#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/joint_paths.hpp"
#include "flatsos/planner/joint_reference.hpp"
#include "flatsos/planner/plan_excitations.hpp"
#include "flatsos/planner/slp.hpp"

namespace flatsos::planner {

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
  Eigen::VectorXd target_q_rad;       ///< the set point (unused when tracking a reference)
  /// Tracking: follow this joint motion instead of coming to rest at the target. The step's path
  /// is the reference from reference_time_s on plus a polynomial correction from the measured state
  /// (fit_tracking_path); the RH controller sets reference_time_s to its own time.
  std::shared_ptr<const JointReference> reference;
  double reference_time_s = 0.0;
  /// The time over which a tracking step's path joins the reference (and its flat outputs reach
  /// alpha from their start); capped at the horizon. Shorter tracks closer but leaves less room
  /// for a plant unlike the model: with a squared effort 0.06 s (the programs' default) holds
  /// plants 20 % weaker or stronger; with the paper's linear one, 0.075 s.
  double tracking_correction_s = 0.075;
  /// A tracking step that starts where the muscles are: the path's acceleration and jerk at 0
  /// (empty: free) and the flat outputs' value and rate (empty: constant
  /// alpha). The RH controller sets them from the plan in use.
  Eigen::VectorXd start_qdd, start_qddd;
  FlatOutputStart flat_start;
  Eigen::VectorXd reserves_N;
  SlpSolver solver = SlpSolver::VertexEnumeration;
  /// Joint torque the muscles need not produce (N m per joint; empty: none): the planned
  /// muscle torques are ID(path) - offset. The RH controller's disturbance observer sets it.
  Eigen::VectorXd torque_offset_N_m;
  PeriodExcitationBounds excitation_bounds;
  /// What each step minimizes over its horizon: null, the map's linear effort by the SLP (another
  /// linear effort is given to the map: FlatOutputMap::withEffort; here it is refused); a
  /// nonlinear one (PowerEffort: squared excitations, activations, stresses) by a sequential QP
  /// from the SLP's alpha or the last step's optimum (receding_horizon/step_effort.hpp).
  std::shared_ptr<const Effort> effort;
};

struct RecedingHorizonStep {
  SolveStatus status = SolveStatus::Failed;
  std::string message;
  JointPath path;                     ///< cubic from (q, qd) to (target, 0) over the horizon, or the tracking path
  Eigen::VectorXd tau_min, tau_max;   ///< torque box over the horizon grid
  /// The SLP's rows G alpha >= B. Constant moment arms: G = C_Y and B = slp_bound_vector of the
  /// box and reserves (m rows). Posture-dependent ones: at each grid posture q_i,
  /// C_Y(q_i) alpha >= reserves - C_tau(q_i) tau_i (grid_points x m rows, exact at the grid).
  /// A tracking step with a start (flat_start): the rows scaled by 1 - phi0 and the start's part
  /// moved to B, at the grid times after 0 and at the first period's excitation samples after 0
  /// ((grid_points - 1 + samples - 1) x m rows).
  Eigen::MatrixXd reserve_rows;
  Eigen::VectorXd bound_N;
  SlpResult slp;                      ///< alpha and its cost (moved inside the bounds when they were imposed)
  Eigen::VectorXd torque_offset_N_m;  ///< the options' offset the step was planned with (may be empty)
  FlatOutputStart flat_start;         ///< where its flat outputs start (empty: constant alpha)
  /// The SLP's optimum left the excitation bounds on the first period and the bounds' sequential
  /// LP moved alpha inside (cost raised); its LP steps.
  bool bounds_imposed = false;
  int bound_iterations = 0;
  /// Newton steps on the last period's active bound rows, taken before any LP step: the step
  /// ended there when bound_iterations is 0 (receding_horizon/period_bounds.hpp).
  int bound_newton_steps = 0;
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
  /// A nonlinear effort's value over the horizon's grid at alpha (options.effort's unit; NaN when
  /// it could not be minimized and the SLP's plan stands) and its sequential QP's iterations (0
  /// for the linear effort).
  double effort_value = 0.0;
  int effort_iterations = 0;
  double wall_seconds = 0.0;
  /// Where the step's time went: the horizon's grid (joint path, inverse dynamics, the SLP's
  /// rows), the SLP (slp.wall_seconds), the excitation bounds (sampling the first period
  /// and, when they bind, their sequential LP) and a nonlinear effort's sequential QP.
  double grid_seconds = 0.0, bounds_seconds = 0.0, effort_seconds = 0.0;
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
    SequentialLpBasis bounds_basis;
    /// ... and the rows active there (bound rows, reserve rows, alpha >= 0; at most alpha's size,
    /// else empty): the next period first holds them at zero by Newton's method
    /// (bounds/active_set_newton.hpp).
    std::vector<int> bounds_active_set;
    /// A nonlinear effort's grid over the horizon and the last step's optimum (its start).
    TorqueJetGrid effort_grid;
    Eigen::VectorXd effort_alpha;
  } buffers;
};

/// Checks RH options against the model: horizon > 0 s, >= 2 grid points, target (unless a
/// reference of the model's joints is tracked, at a finite time) and reserves (>= 0 N) of the
/// model's sizes and finite, a torque offset (if any) of one entry per joint,
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
