#pragma once
// The SOS program's setup: Y as clamped B-splines, the boundary equalities on Y eliminated
// (B-spline coefficients of Y_l = particular + N theta_l), one constraint polynomial per segment
// and muscle (tendon force >= its reserve) or flat output (Y_l >= 0), affine in the free
// coefficients theta, and the LP's cost. Segments: the common refinement of the torque model's
// pieces and the spline's spans, on each of which both are polynomials.

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/numerics/linear_program.hpp"
#include "flatsos/planner/numerics/bspline.hpp"
#include "flatsos/planner/numerics/polynomial.hpp"
#include "flatsos/planner/numerics/spline_trajectory.hpp"
#include "flatsos/planner/sos_program.hpp"
#include "sos/sos_settings.hpp"
#include "flatsos/planner/torque_model.hpp"

namespace flatsos::planner::detail {

/// A constraint is met when its value is >= -this (N). Not 0: where the initial state meets a
/// reserve exactly (a minimum-effort rest on an SLP vertex), rounding leaves values of -1e-14
/// and slopes of -1e-10 next to s = 0 that no plan can lift; the exchange stops chasing them
/// and the certificates prove the constraint + this >= 0.
constexpr double kConstraintTolerance_N = 1e-9;
/// Where the excitation bounds are to be checked, the reserves' exchange first stops at this:
/// once a violated minimum is found its next round's is about a quarter of it (a dip between
/// points halves with each point), and where the bounds bind their own exchange re-runs the
/// reserves' anyway (on the arm at T = 1.5 s: 13 rounds from 0.56 N, 9 of them below 1e-2 N).
constexpr double kLooseConstraintTolerance_N = 1e-2;
/// Where the bounds bind, the reserves' dips near the optimum shrink only fourfold per round: the
/// minimum moves a little between rounds and each new point halves the gap to it, so a dip of
/// 1e-3 N took about seven more rounds to reach kConstraintTolerance_N. A new point whose dip is
/// at most this is imposed with the dip's depth as extra margin, which lifts the row past it at
/// a cost of at most the row's multiplier times this (the arm at T = 1.5 s: 17 -> 9 bounded
/// rounds, +2e-6 of the effort). Not in the reserves-only exchange, whose optimum other solvers
/// must match to 1e-6 (the paper's quartic: +3e-5 with it).
constexpr double kLiftBelow_N = 1e-3;

/// One constraint polynomial on one segment [t0, t1], in the segment's scaled time s in [0, 1],
/// affine in theta: coefficients = base + G theta. It keeps what it constrains, for messages.
struct ConstraintPolynomial {
  Eigen::VectorXd base;
  Eigen::MatrixXd G;
  double t0_s = 0.0, t1_s = 0.0;  ///< the segment
  int piece = 0;              ///< the torque piece holding the segment
  int muscle = -1;            ///< >= 0: tendon-force constraint of this muscle
  int flat_output = -1;       ///< >= 0: Y_l >= 0
  std::string name;           ///< "tendon force of muscle 'biceps'" or "flat output 'co1' >= 0"
  double reserve_N = 0.0;     ///< the muscle's reserve (0 for Y_l >= 0)
  Polynomial remainder_cost_N;  ///< what the torque model's remainder bound costs, in s
  /// The LP imposes the constraint >= margin s^margin_order: where the initial state fixes the
  /// value and slope (the first segment, order 2), a constant margin could not be met at s -> 0.
  int margin_order = 0;
  std::vector<double> points;     ///< where the exchange LP imposes it
  std::vector<bool> sticky;       ///< added by the exchange: never pruned
  /// (s, N): points the LP met only to its own precision (the minimum violated there again by
  /// more than the tolerance): imposed with this much more margin. By position, not index,
  /// because pruning removes points.
  std::vector<std::pair<double, double>> extra_margin;
  Polynomial at(const Eigen::VectorXd& theta) const { return Polynomial(base + G * theta); }
};

/// B-spline coefficients of Y_l = particular + nullspace theta_l (N).
struct OutputParameterization {
  Eigen::VectorXd particular;
  Eigen::MatrixXd nullspace;
  int offset = 0;  ///< of theta_l in theta
};

struct SosSetup {
  SosSetup(double duration, BSplineBasis flat_output_basis) : duration_s(duration), basis(std::move(flat_output_basis)) {}
  double duration_s = 0.0;
  BSplineBasis basis;         ///< of every Y_l
  int free_coefficients = 0;  ///< size of theta
  std::vector<OutputParameterization> outputs;
  std::vector<ConstraintPolynomial> constraints;
  const TorqueModel* torque = nullptr;
  LinearProgram lp;           ///< cost and bounds on theta; rows built by the exchange
  double cost_constant = 0.0; ///< cost = cost_constant + lp.cost . theta
  /// The model's effort effort_cost_constant + effort_cost . theta: lp.cost's but for the
  /// tie-break between tied muscles (tied_muscles.hpp), identical without ties.
  Eigen::VectorXd effort_cost;
  double effort_cost_constant = 0.0;
};

/// [1, s, s^2, ...] (size entries).
Eigen::RowVectorXd monomials(double s, Eigen::Index size);

/// Validates the inputs (std::invalid_argument naming the problem) and builds the program.
SosSetup set_up_sos_program(const FlatOutputMap& flat, const TorqueModel& torque, double duration_s,
                            const FlatOutputBoundary& boundary, const Eigen::VectorXd& reserves_N,
                            const SosSettings& options);

/// A constraint that no free coefficient can change (the equalities fix Y there) and that is
/// violated at one of its points: the program is infeasible for a reason that can be named.
/// Empty when there is none.
std::string fixed_violation(const SosSetup& setup, double margin_N);

/// The exchange LP's rows (setup.lp.G, row_lower, row_upper): every constraint polynomial at its
/// points, >= margin s^margin_order. Returns the number of rows.
int build_exchange_rows(SosSetup& setup, double margin_N);

/// The exact minimum of every constraint polynomial at theta; the violated minima (below
/// -tolerance_N) not yet among a constraint's points join them as sticky points; one
/// that is (the LP met it only to its own precision) gets the full `margin_N` (not scaled by
/// s^margin_order) plus twice the violation as extra margin there. Sets min_value_N to the least
/// minimum; returns whether a point or a margin was added. A new point whose violation is at most
/// `lift_below_N` is imposed with that violation as extra margin (kLiftBelow_N).
bool add_violated_points(SosSetup& setup, const Eigen::VectorXd& theta, double margin_N, double& min_value_N,
                         double tolerance_N = kConstraintTolerance_N, double lift_below_N = 0.0);

/// The flat outputs of theta.
SplineTrajectory flat_outputs_of(const SosSetup& setup, const Eigen::VectorXd& theta);
/// The theta of flat outputs in the program's basis that meet its equalities (flat_outputs_of's inverse).
Eigen::VectorXd theta_of(const SosSetup& setup, const SplineTrajectory& Y);

/// Row l of the boundary equalities' spline (any clamped B-spline basis: flat outputs or joint
/// paths): coefficients = particular + nullspace x, the free coefficients x being B-spline
/// coefficients themselves. Throws std::invalid_argument when the equalities are dependent.
OutputParameterization eliminate_equalities(const BSplineBasis& basis, const FlatOutputBoundary& bc, int l);

}  // namespace flatsos::planner::detail
