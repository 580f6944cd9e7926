#include "flatsos/planner/shortest_transfer.hpp"
#include "flatsos/planner/open_loop_study.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "flatsos/plugin/stopwatch.hpp"

namespace flatsos::planner {

namespace {

void require_search_options(const ShortestTransferOptions& o) {
  if (!(o.lower_s > 0.0) || !std::isfinite(o.lower_s)) throw std::invalid_argument("shortest transfer: lower_s must be > 0 s");
  if (!(o.upper_s > o.lower_s) || !std::isfinite(o.upper_s))
    throw std::invalid_argument("shortest transfer: upper_s must be finite and above lower_s");
  if (!(o.scan_ratio > 0.0 && o.scan_ratio < 1.0)) throw std::invalid_argument("shortest transfer: scan_ratio must be in (0, 1)");
  if (!(o.tolerance_s > 0.0) || !std::isfinite(o.tolerance_s)) throw std::invalid_argument("shortest transfer: tolerance_s must be > 0 s");
  if (o.max_plans < 2) throw std::invalid_argument("shortest transfer: max_plans must be >= 2");
}

std::string seconds_text(double T) {
  std::ostringstream s;
  s.precision(6);
  s << T << " s";
  return s.str();
}

}  // namespace

ShortestTransfer shortest_transfer(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const MuscleState& initial,
                                   const OpenLoopOptions& plan_options, const ShortestTransferOptions& o) {
  return shortest_transfer(flat, workspace, initial, plan_options, o, OpenLoopStudyOptions{});
}

ShortestTransfer shortest_transfer(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const MuscleState& initial,
                                   const OpenLoopOptions& plan_options, const ShortestTransferOptions& o,
                                   const OpenLoopStudyOptions& study) {
  require_search_options(o);
  const Stopwatch wall;
  ShortestTransfer out;
  OpenLoopOptions at = plan_options;
  OpenLoopPlan trial;
  double above = o.upper_s;
  auto plan = [&](double T) {
    at.duration_s = T;
    const Stopwatch one;
    trial = plan_open_loop(flat, workspace, initial, at, study);
    out.tried.push_back({T, trial.status, trial.status == SolveStatus::Solved ? trial.sos.cost_N_s : 0.0, trial.message,
                         one.seconds()});
    return trial.status == SolveStatus::Solved;
  };
  // A duration with a plan becomes the bracket's upper end; one without, its lower end.
  auto record = [&](double T, bool solved) {
    if (solved) {
      above = T;
      out.plan = std::move(trial);
      return;
    }
    out.no_plan_below_s = T;
    out.below_status = trial.status;
    out.below_message = trial.message;
  };
  auto finish = [&](SolveStatus status, std::string message) -> ShortestTransfer {
    out.status = status;
    out.message = std::move(message);
    out.shortest_s = out.plan.status == SolveStatus::Solved ? above : 0.0;
    out.seconds = wall.seconds();
    return std::move(out);  // once, as the function returns
  };

  if (!plan(o.upper_s)) {
    out.plan = std::move(trial);  // says why, as any plan does
    return finish(out.plan.status, "no plan at the longest duration, " + seconds_text(o.upper_s) + ": " + out.plan.message);
  }
  record(o.upper_s, true);
  // Down in steps of scan_ratio to the first duration without a plan: a step stays within that
  // fraction of the least duration, where plans are decided fastest (far below it, a rich basis's
  // plan can creep towards an infeasible optimum for tens of seconds).
  bool bracketed = false;
  for (double T = o.upper_s; T > o.lower_s && !bracketed;) {
    if (static_cast<int>(out.tried.size()) >= o.max_plans)
      return finish(SolveStatus::Failed, "the scan did not reach a duration without a plan in " +
                                             std::to_string(o.max_plans) + " plans");
    T = std::max(o.lower_s, T * o.scan_ratio);
    const bool solved = plan(T);
    record(T, solved);
    bracketed = !solved;
  }
  if (!bracketed) {
    out.at_lower_end = true;
    return finish(SolveStatus::Solved, "a plan at the shortest duration tried, " + seconds_text(o.lower_s));
  }
  while (above - out.no_plan_below_s > o.tolerance_s) {
    if (static_cast<int>(out.tried.size()) >= o.max_plans)
      return finish(SolveStatus::Failed, "the bisection did not reach " + seconds_text(o.tolerance_s) + " in " +
                                             std::to_string(o.max_plans) + " plans");
    const double T = 0.5 * (out.no_plan_below_s + above);
    record(T, plan(T));
  }
  return finish(SolveStatus::Solved, out.below_status == SolveStatus::Infeasible
                                         ? ""
                                         : "the planner could not decide at " + seconds_text(out.no_plan_below_s) +
                                               " (a plan may exist there): the shortest duration is an upper bound");
}

}  // namespace flatsos::planner
