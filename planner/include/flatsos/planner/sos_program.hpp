#pragma once
// The secondary optimization problem (SOP; docs/method/sos_program.md, certificates in sos_certificates.md):
//   minimize  integral_0^T sum_l Y_l(t) dt  over Y in clamped B-splines of degree d with S spans
//             (S = 1: polynomials of degree d; the paper's quartic is d = 4, S = 1)
//   subject to  F_j(t) = C_tau,j tau(t) + C_Y,j Y(t) >= F_reserve,j  and  Y(t) >= 0 on [0, T],
//               boundary equalities on Y and its derivatives at 0 and T.
// tau(t) comes from a TorqueModel (K pieces, degree r, remainder bounds), so on every segment k
// of the common refinement of pieces and spans each constraint is a polynomial in the
// segment's scaled time s in [0, 1] that is affine in the free coefficients theta of Y (the
// boundary equalities are eliminated first):
//   g_jk(s) = C_Y,j Y(s) + C_tau,j p_k(s) - |C_tau,j| e_k(s) - F_reserve,j >= 0.
// Solved by an exchange (cutting-plane) method: an LP in theta imposes the constraints
// at finitely many points; the exact minimum of every g_jk on [0, 1] (roots of g') adds the
// violated points; repeat (the rounds' LPs by an exact simplex, the final one by Ipopt). The
// result is feasible for the semi-infinite program, and the
// pieces that come near zero get Markov-Lukacs SOS certificates. The constraints Y >= 0 are
// imposed only when E has a negative entry (otherwise Y = E F >= 0 follows from the reserves).

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "flatsos/planner/effort.hpp"
#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/joint_paths.hpp"
#include "flatsos/planner/numerics/linear_program.hpp"
#include "flatsos/planner/numerics/polynomial.hpp"
#include "flatsos/planner/numerics/spline_trajectory.hpp"
#include "flatsos/planner/torque_model.hpp"

namespace flatsos::planner {

/// Boundary equalities on the flat outputs Y (p rows each).
struct FlatOutputBoundary {
  Eigen::MatrixXd initial;            ///< p x k0: derivatives 0..k0-1 at t = 0 (k0 may be 0)
  Eigen::MatrixXd terminal;           ///< p x kT: derivatives first..first+kT-1 at t = T
  int terminal_first_order = 1;       ///< 1: Y(T) free, rates fixed (terminal equilibrium)
};

/// Bounds on what the muscles can execute: 0 <= n(t) <= 1 and a_min <= a(t) <= 1 on [0, T].
/// They are nonlinear in Y. When the reserves-only optimum violates them on a dense grid, they
/// are imposed at time points found by exchange on that grid (a sequential LP in a trust region,
/// exact first derivatives through each muscle's inverse, muscles/muscle_inverse.hpp), started
/// from the reserves-only optimum; the reserves stay the exact, certified constraints.
struct ExcitationBoundsOptions {
  bool enforce = true;
  double min_activation = 0.0;       ///< a >= this; 0: each muscle's own activation floor
};

/// The muscles along the plan's fixed joint path: what the bounds need besides the torque model.
struct MusclesAlongPath {
  const FlatOutputMap& flat;
  const JointPath& path;
  plugin::ModelWorkspace& workspace;
};

/// The flat outputs' basis and the bounds (sos_program_study.hpp holds the solver's settings).
struct SosProgramOptions {
  int flat_output_degree = 4;          ///< d (>= 3 keeps the excitations continuous)
  int flat_output_spans = 1;           ///< S knot spans of the B-splines
  /// Each span this many times as long as the one before (1: uniform). A low-effort transfer
  /// spends its effort in a fast start and then settles: short spans there (above 1) put the
  /// coefficients where the forces change.
  double flat_output_span_growth = 1.0;
  ExcitationBoundsOptions bounds;      ///< used when the muscles along the path are given
  /// A nonlinear effort (effort.hpp) to minimize instead of the map's linear one, which then
  /// only finds the start: a sequential QP from its optimum (needs the muscles along the path).
  /// Null: the map's linear effort.
  std::shared_ptr<const Effort> effort;
};

struct SosProgramResult {
  SolveStatus status = SolveStatus::Failed;
  std::string message;                 ///< why, when not solved
  std::string method = "exchange";     ///< the method that solved (or failed): "exchange" or "whole_program_nlp"
  double cost_N_s = 0.0;               ///< integral of sum Y
  /// The flat outputs (N): the optimum when solved; when the bounds are infeasible, the closest
  /// plan found (for diagnosis: it violates them); otherwise none.
  std::optional<SplineTrajectory> Y;
  double min_constraint_value_N = 0.0; ///< exact minimum of every g_jk and Y_l over [0, T]
  int exchange_rounds = 0;
  int lp_points = 0;
  int ipopt_iterations = 0;            ///< summed over all Ipopt calls (exchange LPs and certificates)
  int ipopt_calls = 0;
  std::string ipopt_linear_solver;     ///< what factored those calls' KKT systems (empty: no call)
  int simplex_pivots = 0;              ///< Clp's pivots over the exchange LPs
  int near_active_pieces = 0;          ///< the whole-program NLP: every piece theta moves
  int certified_pieces = 0;            ///< of the near-active ones
  int nlp_variables = 0, nlp_equalities = 0;  ///< of the whole-program NLP (0: not used)
  /// The whole-program NLP: largest l1 norm of a certificate's coefficient residual (N), a bound
  /// on how far below 0 the certified constraint can be besides the 1e-9 N tolerance.
  double max_certificate_residual_N = 0.0;
  bool certified = false;              ///< every near-active piece has a certificate
  bool bounds_imposed = false;         ///< the reserves-only optimum violated a bound: the NLP ran
  int bound_rounds = 0;                ///< NLP solves
  int bound_points = 0;                ///< times at which the NLP imposed the bounds
  int bound_sequential_lp_iterations = 0;        ///< LP steps of the sequential LP, over all rounds
  int bound_slp_iterations = 0;  ///< deprecated: bound_sequential_lp_iterations, kept for existing callers
  /// Largest excess of a or n over its bounds on the check grid (<= tolerance when solved; 0
  /// without bounds).
  double max_bound_excess = 0.0;
  double setup_seconds = 0.0, solve_seconds = 0.0, certify_seconds = 0.0;
  double bounds_seconds = 0.0;         ///< checks and NLP solves of the bounds (part of solve_seconds)
  /// What the plan minimized: SosProgramOptions::effort's name, value (its Gauss-Legendre
  /// quadrature) and unit; for the map's linear effort "tendon_force", cost_N_s and its unit.
  std::string effort_name;
  double effort_value = 0.0;
  std::string effort_unit;
  int effort_rounds = 0, effort_iterations = 0;  ///< the nonlinear effort's exchange rounds and QP steps
  double effort_seconds = 0.0;         ///< minimizing the nonlinear effort (part of solve_seconds)
};

/// Throws std::invalid_argument for bad sizes, NaN, T <= 0, a negative reserve or a basis too
/// small for the equalities.
/// With `muscles` (and options.bounds.enforce) the excitation and activation bounds are part of
/// the program. The solver's settings are the measured defaults (sos_program_study.hpp).
SosProgramResult solve_sos_program(const FlatOutputMap& flat, const TorqueModel& torque, double duration_s,
                                   const FlatOutputBoundary& boundary, const Eigen::VectorXd& reserves_N,
                                   const SosProgramOptions& options = {}, const MusclesAlongPath* muscles = nullptr);

}  // namespace flatsos::planner
