#pragma once
// The direct-collocation reference (docs/method/collocation.md): the open-loop minimum-effort
// problem the flatness planner solves, transcribed the way OpenSim Moco and most optimal-control
// codes do it, so that its optimum is the yardstick for the flatness plans and users get a
// baseline:
//   minimize  integral_0^T sum_j l_j(F_j, a_j, n_j) dt   (the effort, effort.hpp)
//   over the muscle states (tendon length, activation), excitations and fibre velocities,
//   subject to the Hill muscle's laws (muscles/), the joint torques A F = ID(q(t)) along a
//   prescribed joint path, F_j >= reserve_j, 0 <= n <= 1, a_min <= a <= 1, the initial muscle
//   state, and rest at T (dL_S/dt = da/dt = 0).
// Hermite-Simpson collocation (separated form: states and controls at mesh points and interval
// midpoints) on a uniform mesh, the fibre equilibrium as an implicit constraint (no division by
// the activation), solved by Ipopt with exact sparse first and second derivatives.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <memory>
#include <string>

#include <Eigen/Core>

#include "flatsos/planner/effort.hpp"
#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/joint_paths.hpp"
#include "flatsos/planner/solve_status.hpp"

namespace flatsos::planner {

struct CollocationOptions {
  int mesh_intervals = 100;          ///< K intervals: 2K + 1 collocation points
  /// Each interval this many times as long as the one before (1: uniform; above 1: short
  /// intervals at t = 0, where a transfer from rest starts fast and the activations change
  /// within milliseconds).
  double mesh_interval_growth = 1.0;
  /// What to minimize: null means the flatness planner's own effort, w^T F with the model's
  /// effort_weights (FlatOutputMap::effortWeights).
  std::shared_ptr<const Effort> effort;
  /// Deprecated (use effort = TendonForceEffort(w)): per-muscle weights of w^T F, used when
  /// `effort` is null and this is not empty; kept so existing callers still run.
  Eigen::VectorXd effort_weights;
  double min_activation = 0.0;       ///< a >= this; 0: each muscle's own activation floor
  double tolerance = 1e-9;           ///< Ipopt's tol (scaled NLP error)
  int max_iterations = 3000;
};

struct CollocationResult {
  SolveStatus status = SolveStatus::Failed;
  std::string message;               ///< why, when not solved
  std::string solver_status;         ///< Ipopt's return status
  std::string linear_solver;         ///< what factored Ipopt's KKT systems
  double cost = 0.0;                 ///< the effort: Simpson quadrature of its integrand
  std::string cost_unit;             ///< Effort::unit(): "N s" for tendon forces, "s" otherwise
  double cost_N_s = 0.0;             ///< deprecated: cost, kept for existing callers
  int mesh_intervals = 0;
  int variables = 0, constraints = 0;
  int iterations = 0;
  double setup_seconds = 0.0;        ///< inverse dynamics and path lengths at the points
  double solve_seconds = 0.0;        ///< the start (the inverse map at every point) and Ipopt
  Eigen::VectorXd time_s;            ///< the 2K + 1 collocation points
  /// m x (2K + 1), one row per muscle. Between the points each state is the cubic through its
  /// values and rates at the interval's ends (Hermite-Simpson's own representation), and the
  /// excitation is the one that cubic implies.
  Eigen::MatrixXd tendon_force_N, tendon_length_m, activation, excitation, shortening_velocity_m_per_s;
  Eigen::MatrixXd activation_rate_per_s;  ///< da/dt of each muscle's activation dynamics
  /// N x (2K + 1): the joint path at the points (the prescribed one, or the optimized one).
  Eigen::MatrixXd joint_angle_rad, joint_speed_rad_per_s, joint_acceleration_rad_per_s2;
};

/// The weights of the flat outputs' cost: integral sum_l Y_l = integral (E^T 1)^T F.
Eigen::VectorXd flat_output_effort_weights(const FlatOutputMap& flat);

/// The minimum-effort excitations along a prescribed joint path (for the flatness planner's own:
/// OpenLoopPlan::path) from the initial muscle state (its tendon lengths and activations) to
/// rest at path.duration_s. Throws std::invalid_argument naming the field for bad sizes, NaN,
/// negative reserves or weights, fewer than 1 mesh interval, an initial state outside the
/// muscles' domain; solver outcomes come back as statuses (Infeasible when Ipopt finds the
/// problem infeasible).
CollocationResult solve_collocation_along_path(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                               const JointPath& path, const MuscleState& initial,
                                               const Eigen::VectorXd& reserves_N, const CollocationOptions& options = {});

/// The same along a measured motion (the inverse problem's reference, what MocoInverse solves):
/// the muscles' states free at both ends (no initial state, no rest at T), the torque rows at
/// every point. Moment arms may depend on posture. Same errors and statuses.
CollocationResult solve_collocation_along_motion(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                                 const JointPath& path, const Eigen::VectorXd& reserves_N,
                                                 const CollocationOptions& options = {});

/// The same problem with the joint path free too (the predictive problem): q, qd and qdd become
/// unknowns at every point, joined by Hermite-Simpson's defects (q' = qd, qd' = qdd), the
/// torques the model's inverse dynamics of them, the muscles' lengths functions of q. The path
/// keeps its ends: start_path's q and qd at t = 0, and its q at the end with rest (qd = qdd = 0;
/// start_path must end at rest). start_path is also the start of the solve. Same errors and
/// statuses as solve_collocation_along_path.
CollocationResult solve_collocation_free_path(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                              const JointPath& start_path, const MuscleState& initial,
                                              const Eigen::VectorXd& reserves_N, const CollocationOptions& options = {});

}  // namespace flatsos::planner
