#pragma once
// A nonlinear effort (effort.hpp) summed over time points whose tendon-force jets move affinely
// with coefficients theta (BoundPoint, bound_rows.hpp), with its gradient and Gauss-Newton
// Hessian in theta: each muscle's term's second derivatives times the outer products of the
// gradients of F, a and n, which come exactly through the muscle's inverse
// (muscles::invert_muscle). The sequential QPs of the receding-horizon step
// (receding_horizon/step_effort.hpp) and of the open-loop plan (sos/effort_exchange.hpp) minimize
// it.

#include <vector>

#include <Eigen/Core>

#include "bounds/bound_rows.hpp"
#include "flatsos/planner/effort.hpp"

namespace flatsos::planner::detail {

struct EffortModel {
  double value = 0.0;
  Eigen::VectorXd gradient;
  Eigen::MatrixXd hessian;  // Gauss-Newton: positive semidefinite for a convex term
};

/// sum_i weights_s[i] sum_j l_j at points[i] for theta into `out` (its derivatives only when
/// asked for). False where a muscle leaves its domain (no activation gives the forces) or a value
/// is not finite: `out` is then unusable. Where no excitation gives the activation's rate (a
/// faster deactivation than n = 0 allows), false too unless `closest_excitation`: the term then
/// takes the inverse's closest excitation, its gradient by central differences (a point outside
/// the excitation bounds, which their own rows push back in).
bool evaluate_effort(const FlatOutputMap& flat, const Effort& effort, const std::vector<BoundPoint>& points,
                     const std::vector<double>& weights_s, const Eigen::VectorXd& theta, bool derivatives,
                     EffortModel& out, bool closest_excitation = false);

/// The bound rows `at` (with their Jacobian) as the first rows of a QP's J d >= lower, linearized:
/// a violated row is asked to clear; a row no coefficient moves (at t = 0 of a plan that starts
/// from the muscles' state) only not to get worse. J must have at least as many rows as `at`,
/// zero in those rows.
void place_linearized_bound_rows(const BoundRowsAt& at, Eigen::MatrixXd& J, Eigen::VectorXd& lower);

}  // namespace flatsos::planner::detail
