#pragma once
// Private helpers for the planner's Ipopt problems (C++ TNLP interface only: Simbody's
// libSimTKmath exports Ipopt's C-API symbol names, DESIGN.md 7).
#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>

#include <string>

namespace flatsos::planner::detail {

/// A quiet Ipopt application with MUMPS (the only linear solver of Debian's Ipopt). Initialize("")
/// so that no stray ipopt.opt in the working directory is read.
Ipopt::SmartPtr<Ipopt::IpoptApplication> make_ipopt(double tol, int max_iter);

/// Ipopt's status as text, for messages.
std::string ipopt_status_name(Ipopt::ApplicationReturnStatus status);

/// Whether the status means a usable optimum (Solve_Succeeded or Solved_To_Acceptable_Level).
bool ipopt_solved(Ipopt::ApplicationReturnStatus status);
/// Whether Ipopt says the problem is infeasible.
bool ipopt_infeasible(Ipopt::ApplicationReturnStatus status);

}  // namespace flatsos::planner::detail
