#pragma once
// Primary motion planning (PMPP): one polynomial per joint through boundary derivatives.
// Open loop: degree 8 from (q, qd, qdd, q''') at 0 to (q_T, 0, 0, 0, 0) at T; receding horizon:
// a cubic from (q, qd) to (q_T, 0). A joint path the planner optimizes (free path) is a clamped
// B-spline through the same boundary derivatives instead.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/numerics/polynomial.hpp"
#include "flatsos/planner/numerics/spline_trajectory.hpp"

namespace flatsos::planner {

class JointReference;

struct JointPath {
  double duration_s = 0.0;
  std::vector<Polynomial> q;  ///< per joint, ascending powers of t (s), radians (empty with a spline)
  std::optional<SplineTrajectory> spline;  ///< a free path: one row per joint (radians); then q is empty
  /// Tracking: the path is the reference at reference_start_s + t plus the polynomials q (the
  /// correction from the measured state; see fit_tracking_path).
  std::shared_ptr<const JointReference> reference;
  double reference_start_s = 0.0;
  double correction_end_s = 0.0;  ///< with a reference: q applies on [0, correction_end_s] only
  /// A path given by a spline (one row per joint) over its basis' duration.
  static JointPath fromSpline(SplineTrajectory spline);
  int numJoints() const { return spline ? spline->signals() : static_cast<int>(q.size()); }
  /// N x orders jet (derivatives 0..orders-1) at time t; beyond [0, duration_s] the path continues
  /// its end polynomials (a spline path: its end spans').
  Jet jet(double t, int orders = 5) const;
  /// The same into `out` (N x orders, orders = its column count; allocates nothing).
  void jetInto(double t, Eigen::Ref<Jet> out) const;
};

/// The receding-horizon path that follows a reference from time t_s on: the reference over the
/// horizon T plus, per joint, a polynomial correction from the measured state's offset from the
/// reference at t_s (value and speed, and acceleration and jerk when qdd is not empty) to zero
/// value, speed, acceleration and jerk at correction_s, after which the path is the reference. Written
/// into `out` (no allocation when it already holds N polynomials of that degree). Throws
/// std::invalid_argument for T <= 0, a correction time outside (0, T], mismatched sizes or a
/// state that is not finite.
void fit_tracking_path(double duration_s, double correction_s, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                       const Eigen::VectorXd& qdd, const Eigen::VectorXd& qddd,
                       std::shared_ptr<const JointReference> reference, double t_s, JointPath& out);

/// Torque jets along the path at the `count` times i h: for a polynomial path by the map's
/// differences in time (FlatOutputMap::torqueJetsOnGrid: about one inverse dynamics per time),
/// for a spline path exactly at each time (differences straddling its knots, where the path is
/// only degree - 1 times differentiable, lose the fast spans' torque rates).
std::vector<TorqueJet> torque_jets_on_grid(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                           const JointPath& path, double h, int count);

/// initial: N x k0 (derivatives 0..k0-1 at 0), terminal: N x kT (derivatives 0..kT-1 at T).
/// Degree k0 + kT - 1. Throws std::invalid_argument for T <= 0, mismatched rows or NaN.
JointPath fit_joint_path(double duration_s, const Eigen::MatrixXd& initial, const Eigen::MatrixXd& terminal);

/// The receding-horizon path: per joint the cubic from (q, qd) at 0 to (q_target, 0) at T, in
/// closed form (fit_joint_path's result with initial [q qd], terminal [q_target 0]). Written
/// into `out`, reusing its storage: no allocation when `out` already holds N cubics. Throws
/// std::invalid_argument for T <= 0, mismatched sizes or NaN.
void fit_rest_cubic(double duration_s, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                    const Eigen::VectorXd& q_target, JointPath& out);

}  // namespace flatsos::planner
