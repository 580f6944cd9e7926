#pragma once
// The joint path as part of the optimization (the predictive problem, not only the redundancy
// along a given path; docs/method/free_path.md): each joint a clamped B-spline through the same
// boundary derivatives as the degree-8 path (q..q''' at 0, rest at T). Its free coefficients c
// minimize V(c), the bounded plan's cost along the path of c at time points found by exchange;
// then the plan along the optimized path is made and certified as along any path. Needs the
// excitation bounds (without them a path that moves faster always costs less).
// free_path_study.hpp holds the method's settings.

#include <string>

namespace flatsos::planner {

/// How the joint path's coefficients move.
enum class FreePathMethod {
  /// BFGS on the bounded plan's cost as a function of the path, with the gradient from the
  /// bounded plan's multipliers: fastest on few path spans, far too slow on many.
  ReducedQuasiNewton,
  /// One Ipopt problem over the plan and the path per exchange round, exact first derivatives
  /// and a Hessian from them: the same optimum on few spans, and it still converges on 24-48.
  JointNewton,
};

/// "reduced_quasi_newton" or "joint_newton": the names the programs and summaries use.
constexpr const char* to_string(FreePathMethod m) {
  return m == FreePathMethod::ReducedQuasiNewton ? "reduced_quasi_newton" : "joint_newton";
}
/// The method of that name; std::invalid_argument naming the accepted ones otherwise.
FreePathMethod free_path_method(const std::string& name);

struct FreeJointPathOptions {
  bool enabled = false;
  int spans = 6;              ///< of each joint's spline (degree 8 by default)
  /// Each span this many times as long as the one before (1: uniform). A low-effort transfer
  /// starts fast and settles slowly, so its path needs short spans near t = 0.
  double span_growth = 1.0;
};

/// What optimizing the joint path did (OpenLoopOptions::free_path). With a nonlinear effort
/// (OpenLoopOptions::effort) the costs below are its values, in its unit.
struct FreePathReport {
  bool optimized = false;         ///< the path was optimized and the plan is along it
  /// The plan along the degree-8 path that started the path stage, in its basis of
  /// start_flat_output_spans spans (FreePathStudyOptions::start_min_spans; 0 when it has none).
  double prescribed_cost_N_s = 0.0;
  std::string prescribed_status;  ///< of that plan: "solved", "infeasible", ...
  int start_flat_output_spans = 0;
  double cost_at_points_N_s = 0.0;   ///< the path optimization's own cost (exact torques at its points)
  FreePathMethod method = FreePathMethod::ReducedQuasiNewton;
  int rounds = 0, points = 0;     ///< exchange rounds, time points
  /// Quasi-Newton steps (ReducedQuasiNewton) or Ipopt iterations (JointNewton), then V(c)
  /// evaluations and their LP steps (ReducedQuasiNewton only).
  int path_iterations = 0, evaluations = 0, sequential_lp_iterations = 0;
  int slp_iterations = 0;  ///< deprecated: sequential_lp_iterations, kept for existing callers
  /// The torque model of the plan along the optimized path: its pieces (the options' pieces,
  /// doubled FreePathStudyOptions::max_torque_refinements times at most) and how many plans along
  /// the path were made.
  int final_torque_pieces = 0, final_plans = 0;
  double seconds = 0.0;
};

}  // namespace flatsos::planner
