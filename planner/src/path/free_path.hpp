#pragma once
// The joint path as part of the optimization (free_path.hpp;
// docs/method/free_path.md). Each joint is a clamped B-spline through the open-loop plan's
// boundary derivatives; its free coefficients c are optimized in reduced space:
//   V(c) = min over theta of  cost . theta   (the effort: sum_l of the integral of Y_l)
//          subject to, at time points found by exchange on a dense grid, for every muscle
//          F_j = C_tau,j tau(q(c)) + C_Y,j Y(theta) >= reserve_j, Y_l >= 0, and the four bound rows
//          of a and n,
// which for fixed c is the prescribed-path bounded plan (the bounds' sequential LP) at those
// points. Its gradient is exact by the envelope theorem: dV/dc = -sum_k lambda_k d g_k / d c with
// the plan's multipliers lambda and the rows' derivatives in c (torque jets and their gradients
// from the pin tree in dual numbers, the muscle inverse's gradients in the force and length jets).
// A quasi-Newton method on c alone (a handful of coefficients) supplies the curvature a joint
// sequential LP lacks (its optimum is not a vertex in c: that LP only creeps). Every accepted c
// has a plan that meets every row at the points, so the iteration only ever improves a valid plan.
// The result is a path; the caller plans along it as along any path (torque model, exchange,
// bounds, certificates), so the final plan is certified exactly as a prescribed-path plan is.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "flatsos/planner/joint_paths.hpp"
#include "path/free_path_settings.hpp"
#include "sos/sos_setup.hpp"

namespace flatsos::planner::detail {

struct FreePathOutcome {
  bool converged = false;
  std::string failure;           // why not
  JointPath path;                // the optimized path (a spline)
  Eigen::VectorXd theta;         // the flat outputs' coefficients on it (setup's basis)
  double cost_N_s = 0.0;         // at the exchange points (the planner's final cost certifies it)
  bool infeasible = false;       // no plan at the points even along the start path
  int rounds = 0, points = 0;
  std::vector<double> times_s;   // the exchange's time points
  int path_iterations = 0, evaluations = 0, sequential_lp_iterations = 0;
  // On the dense grid at the last check (before the last round when the exchange ended on a
  // small change of cost: FreePathStudyOptions::exchange_relative_tolerance).
  double worst_bound_excess = 0.0, min_reserve_margin_N = 0.0;
};

/// From theta (in setup's flat-output basis, on `start_path`), the joint path's spline from its
/// boundary derivatives (initial: N x 4, q..q''' at 0; target: rest there). setup supplies the
/// flat outputs' parameterization and cost (its torque model is not used).
FreePathOutcome optimize_joint_path(const SosSetup& setup, const FlatOutputMap& flat, const JointPath& start_path,
                                    const Eigen::MatrixXd& initial_q_jet, const Eigen::VectorXd& target_q_rad,
                                    const Eigen::VectorXd& theta, const Eigen::VectorXd& reserves_N,
                                    const Eigen::VectorXd& a_min, const FreePathSettings& options);

/// The path's free coefficients c closest to `path` (exact when the spline holds it), and the
/// path of c: the optimization's coordinates, for tests.
Eigen::VectorXd path_coefficients(const SosSetup& setup, const JointPath& path, const Eigen::MatrixXd& initial_q_jet,
                                  const Eigen::VectorXd& target_q_rad, const FreePathSettings& options);
JointPath path_of(const SosSetup& setup, const Eigen::VectorXd& c, const Eigen::MatrixXd& initial_q_jet,
                  const Eigen::VectorXd& target_q_rad, const FreePathSettings& options);

/// V(c) at the given time points, the plan's theta there and dV/dc (the envelope gradient), with
/// the plan's SLP started from theta_start: what the optimization evaluates, for tests.
struct PathValue {
  bool ok = false;
  std::string failure;
  double cost_N_s = 0.0;
  Eigen::VectorXd theta, gradient;
  int active_reserve_rows = 0, active_bound_rows = 0;  ///< rows with a multiplier above 0
};
PathValue path_value(const SosSetup& setup, const FlatOutputMap& flat, const Eigen::MatrixXd& initial_q_jet,
                     const Eigen::VectorXd& target_q_rad, const Eigen::VectorXd& reserves_N, const Eigen::VectorXd& a_min,
                     const FreePathSettings& options, const std::vector<double>& times_s, const Eigen::VectorXd& c,
                     const Eigen::VectorXd& theta_start);

}  // namespace flatsos::planner::detail
