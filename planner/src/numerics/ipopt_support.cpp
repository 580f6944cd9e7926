#include "numerics/ipopt_support.hpp"

#include <mutex>
#include <stdexcept>

namespace flatsos::planner::detail {

IpoptSession make_ipopt(double tol, int max_iter) {
  static std::recursive_mutex mumps;
  IpoptSession session{std::unique_lock<std::recursive_mutex>(mumps), IpoptApplicationFactory()};
  Ipopt::IpoptApplication* app = Ipopt::GetRawPtr(session.app);
  app->Options()->SetIntegerValue("print_level", 0);
  app->Options()->SetStringValue("sb", "yes");  // no banner
  app->Options()->SetStringValue("linear_solver", "mumps");
  app->Options()->SetNumericValue("tol", tol);
  app->Options()->SetIntegerValue("max_iter", max_iter);
  if (app->Initialize("") != Ipopt::Solve_Succeeded)
    throw std::runtime_error("Ipopt failed to initialize");
  return session;
}

std::string ipopt_status_name(Ipopt::ApplicationReturnStatus s) {
  switch (s) {
    case Ipopt::Solve_Succeeded: return "Solve_Succeeded";
    case Ipopt::Solved_To_Acceptable_Level: return "Solved_To_Acceptable_Level";
    case Ipopt::Infeasible_Problem_Detected: return "Infeasible_Problem_Detected";
    case Ipopt::Search_Direction_Becomes_Too_Small: return "Search_Direction_Becomes_Too_Small";
    case Ipopt::Diverging_Iterates: return "Diverging_Iterates";
    case Ipopt::User_Requested_Stop: return "User_Requested_Stop";
    case Ipopt::Feasible_Point_Found: return "Feasible_Point_Found";
    case Ipopt::Maximum_Iterations_Exceeded: return "Maximum_Iterations_Exceeded";
    case Ipopt::Restoration_Failed: return "Restoration_Failed";
    case Ipopt::Error_In_Step_Computation: return "Error_In_Step_Computation";
    case Ipopt::Maximum_CpuTime_Exceeded: return "Maximum_CpuTime_Exceeded";
    case Ipopt::Not_Enough_Degrees_Of_Freedom: return "Not_Enough_Degrees_Of_Freedom";
    case Ipopt::Invalid_Problem_Definition: return "Invalid_Problem_Definition";
    case Ipopt::Invalid_Option: return "Invalid_Option";
    case Ipopt::Invalid_Number_Detected: return "Invalid_Number_Detected";
    default: return "Ipopt_Error_" + std::to_string(static_cast<int>(s));
  }
}

bool ipopt_solved(Ipopt::ApplicationReturnStatus s) {
  return s == Ipopt::Solve_Succeeded || s == Ipopt::Solved_To_Acceptable_Level;
}

bool ipopt_infeasible(Ipopt::ApplicationReturnStatus s) {
  return s == Ipopt::Infeasible_Problem_Detected;
}

}  // namespace flatsos::planner::detail
