#pragma once
// The outcome of every solve the planner reports (Moco's convention: a failed solve is marked as
// failed, never silently usable).

namespace flatsos::planner {

/// Solved: a usable optimum; Infeasible: the problem has no solution (the message says why);
/// Failed: the solver did not reach an answer.
enum class SolveStatus { Solved, Infeasible, Failed };

/// "solved", "infeasible", "failed" (the names in summaries and .sto headers).
constexpr const char* to_string(SolveStatus s) {
  switch (s) {
    case SolveStatus::Solved: return "solved";
    case SolveStatus::Infeasible: return "infeasible";
    case SolveStatus::Failed: return "failed";
  }
  return "failed";
}

}  // namespace flatsos::planner
