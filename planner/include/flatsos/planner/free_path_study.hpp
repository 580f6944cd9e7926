#pragma once
// The free joint path's study settings (free_path.hpp): its method, degree, exchange grid,
// tolerances and iteration caps. The defaults are the product's.

#include "flatsos/planner/free_path.hpp"

namespace flatsos::planner {

struct FreePathStudyOptions {
  FreePathMethod method = FreePathMethod::ReducedQuasiNewton;
  int degree = 8;             ///< >= 5 (q'''' continuous); 8 holds the prescribed path exactly
  int points_per_span = 2;    ///< of the flat outputs' spans, imposed from the start
  /// The plan along the prescribed path only starts the path stage, so it is made in the
  /// coarsest basis nested in the flat outputs' (every f-th of their S breakpoints: S / f spans
  /// growing by growth^f, f the largest divisor of S) with at least this many spans, and carried
  /// into the flat outputs' basis exactly. When the coarse plan is not solved, the flat outputs'
  /// own basis plans it. 0 (or S and above): the flat outputs' own basis.
  int start_min_spans = 16;
  int check_points = 3001;    ///< the dense grid on which the exchange looks for violations
  /// Allowed excess of a and n and reserve deficit on that grid while the path moves. The plan
  /// along the final path meets the SOS program's own tolerances: these only decide when the
  /// path's points suffice.
  double tolerance = 1e-4;
  double tolerance_N = 1e-3;
  /// JointNewton: the exchange also ends once a round (after the first) changed the cost at the
  /// points by at most this fraction (0.1 %: the resolution at which the collocation reference's
  /// mesh counts as converged). 0: only when the grid holds.
  double exchange_relative_tolerance = 1e-3;
  double relative_tolerance = 1e-6;  ///< stop when a step lowers the cost by less than this fraction
  int max_rounds = 20;
  int max_path_iterations = 200;  ///< quasi-Newton steps per exchange round
  int max_sequential_lp_iterations = 200;   ///< sequential-LP steps per evaluation of V(c)
  int max_newton_iterations = 1000;  ///< Ipopt iterations per exchange round (JointNewton)
  /// The plan along the optimized path gets its own torque model, and the optimized path is
  /// faster than the prescribed one: its pieces may not follow it. They double (their growth its
  /// square root, keeping the grading), at most `max_torque_refinements` (0 to 10) times, while
  /// that plan fails or costs more than `torque_model_relative_gap` above the path stage's cost
  /// at its points (exact torques).
  int max_torque_refinements = 3;
  double torque_model_relative_gap = 5e-3;
};

}  // namespace flatsos::planner
