#pragma once
// The shortest transfer time the planner can plan (docs/method/shortest_transfer.md): the least
// duration T for which plan_open_loop finds a plan the muscles can execute (excitations in
// [0, 1], activations in [floor, 1], reserves met), for a given start, target and formulation.
// Found by scanning downwards from `upper` (which must have a plan) in steps of a fixed ratio,
// T_k = upper r^k (and `lower` last), to the first T without one, then bisecting between that T
// and the one above it:
// the lower end of the interval of durations with a plan that holds `upper`. Far below that end
// the plans are far from feasible and the slowest to decide, so the search stays near it.

#include <string>
#include <vector>

#include "flatsos/planner/open_loop.hpp"

namespace flatsos::planner {

struct ShortestTransferOptions {
  double lower_s = 0.1;      ///< the shortest duration tried (> 0)
  double upper_s = 3.0;      ///< the longest (a plan usually exists there)
  double scan_ratio = 0.8;   ///< in (0, 1): each scanned duration is this fraction of the one before
  double tolerance_s = 1e-3; ///< the bisection stops at a plan at T and none at T - d, d <= this
  int max_plans = 60;        ///< plans at most (scan and bisection together)
};

/// One planned duration of the search.
struct TriedDuration {
  double duration_s = 0.0;
  SolveStatus status = SolveStatus::Failed;
  double cost_N_s = 0.0;  ///< when solved
  std::string message;    ///< why not, when not solved
  double seconds = 0.0;   ///< the plan's wall time
};

struct ShortestTransfer {
  /// Solved: shortest_s has a plan and (unless at_lower_end) no_plan_below_s has none, at most
  /// tolerance_s shorter. Infeasible: no plan at `upper` (the message says why). Failed: the plan at
  /// `upper` failed, or the search ran out of plans (shortest_s then holds the shortest plan found).
  SolveStatus status = SolveStatus::Failed;
  std::string message;
  double shortest_s = 0.0;       ///< the shortest duration found with a plan
  double no_plan_below_s = 0.0;  ///< the longest duration below it found without one (0: none)
  /// The planner's verdict there: Infeasible (proven: no plan in this formulation) or Failed (the
  /// solver did not decide; a plan may exist, so shortest_s is an upper bound only).
  SolveStatus below_status = SolveStatus::Infeasible;
  std::string below_message;     ///< the planner's message there
  bool at_lower_end = false;     ///< a plan exists at options.lower_s: the least duration may be shorter
  OpenLoopPlan plan;             ///< the plan at shortest_s; without one, the plan at `upper` (why not)
  std::vector<TriedDuration> tried;  ///< every planned duration, in the order planned
  double seconds = 0.0;
};

/// The shortest duration in [options.lower_s, options.upper_s] for which plan_open_loop (with
/// `plan_options`, whose duration_s is ignored) finds a plan from `initial`. Throws
/// std::invalid_argument naming the field for bad search options and whatever plan_open_loop
/// throws for bad plan options.
ShortestTransfer shortest_transfer(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const MuscleState& initial,
                                   const OpenLoopOptions& plan_options, const ShortestTransferOptions& options);

}  // namespace flatsos::planner
