#pragma once
// The excitation and activation bounds of the SOS program (sos_program.hpp,
// ExcitationBoundsOptions): checked on a dense grid, and when violated imposed by an NLP at
// exchange points, with the reserves' exchange rows as its linear constraints.

#include <vector>

#include <Eigen/Core>

#include "flatsos/planner/numerics/simplex_lp.hpp"
#include "flatsos/planner/sos_program.hpp"
#include "sos/sos_setup.hpp"

namespace flatsos::planner::detail {

/// An earlier plan of the same transfer along a nearby joint path (the free path's): the bounded
/// exchange starts from its flat outputs' coefficients (the program's basis) with its time points
/// imposed from the first round, instead of finding the points round by round from the reserves'
/// optimum (the arm's free path, before kLiftBelow_N: 24 rounds and 0.40 s instead of 31 and
/// 0.74 s).
struct BoundsWarmStart {
  Eigen::VectorXd theta;
  std::vector<double> times_s;  // within [0, T]
  /// The whole check grid is searched in every round in which every tenth grid time shows no new
  /// violation, also while the reserves' dips are still being chased, not only once they hold. A
  /// plan that starts near its optimum has the violations only the whole grid sees from its first
  /// round (they come from the new torque model, not from the plan's moves), and their points then
  /// join beside the dips instead of after them: the arm's free path 14 -> 8 rounds, 0.17 ->
  /// 0.13 s, the same plan (docs/method/free_path.md, "Speed", (vi)). From the reserves' optimum
  /// the plan moves far in its first rounds, and whole-grid searches there cost more than the
  /// rounds they save, so a cold start keeps them until the reserves' dips are small (or hold).
  bool whole_grid_every_round = true;
};

/// Starts from theta, the reserves-only optimum with its exchange stopped at
/// kLooseConstraintTolerance_N; where the bounds hold there on every tenth grid time, the
/// reserves' exchange is finished first (from its points and `basis`). When a bound is violated
/// on the check grid, solves the bounded NLP (and re-runs the reserves' exchange inside it) until
/// the grid and the constraint polynomials hold. Fills the bound fields of `result` and, when it
/// fails, status and message; returns whether theta is a bounded, reserve-feasible optimum.
/// `basis`: the exchange's last basis, where the sequential LP's step LPs start (most reserve rows
/// keep their status; from scratch the first step LP took 484 pivots on the arm at T = 1.5 s).
/// `warm`: when the bounds bind, the rounds start from it instead.
bool impose_excitation_bounds(SosSetup& setup, const MusclesAlongPath& muscles, const SosSettings& options,
                              Eigen::VectorXd& theta, SosProgramResult& result, SequentialLpBasis basis = {},
                              const BoundsWarmStart* warm = nullptr);

/// solve_sos_program (sos_program.hpp) with the bounded exchange started from `warm`.
SosProgramResult solve_sos_program_from(const FlatOutputMap& flat, const TorqueModel& torque, double duration_s,
                                        const FlatOutputBoundary& boundary, const Eigen::VectorXd& reserves_N,
                                        const SosSettings& options, const MusclesAlongPath& muscles,
                                        const BoundsWarmStart& warm);

/// Only checks the bounds at theta on the whole check grid (for solvers that do not impose them):
/// fills max_bound_excess and bounds_seconds; when a bound is exceeded, sets status Failed and a
/// message naming the worst excess, and returns false.
bool check_excitation_bounds(const SosSetup& setup, const MusclesAlongPath& muscles, const SosSettings& options,
                             const Eigen::VectorXd& theta, SosProgramResult& result);

}  // namespace flatsos::planner::detail
