#pragma once
// V(c), the reduced-space value function of the free joint path (path/free_path.hpp): for the
// path of c, the plan's minimum of the effort over theta at the exchange's time points, and its
// gradient in c by the envelope theorem. The map's linear effort (cost . theta) is minimized by
// the bounds' sequential LP; a nonlinear effort (effort.hpp) by its sequential QP
// (bounds/effort_sqp.hpp) on its quadrature along the path, whose own partial derivative in c
// joins the rows' term.

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "bounds/effort_sqp.hpp"
#include "bounds/sequential_lp.hpp"
#include "path/path_effort.hpp"
#include "path/path_rows.hpp"

namespace flatsos::planner::detail {

struct RowsAlongPath;

// V(c), theta there and dV/dc, and the SLP's state to start the next evaluation from.
struct Evaluation {
  bool ok = false;
  std::string failure;
  double cost_N_s = std::numeric_limits<double>::infinity();
  Eigen::VectorXd c, theta, gradient;
  SequentialLpBasis basis;
  double radius = 0.0;
  int sequential_lp_iterations = 0;
  int active_reserve_rows = 0, active_bound_rows = 0;
  EffortSqpActiveRows effort_rows;  // a nonlinear effort's last QP's active rows: the next V's start
  int effort_qp_row_changes = 0;    // its QPs' active-set changes (EffortSqp::qpRowChanges)
};

class ValueFunction {
 public:
  ValueFunction(const SosSetup& setup, const FlatOutputMap& flat,
                const std::vector<PathPoint>& points, const PathParameterization& P,
                const Eigen::VectorXd& reserves, const Eigen::VectorXd& a_min,
                int max_sequential_lp_iterations, const PathEffort* effort);

  int evaluations = 0, sequential_lp_iterations = 0;

  /// V at c, its optimizer started from `from` (theta; for the linear effort also the SLP's basis
  /// and radius).
  Evaluation operator()(const Eigen::VectorXd& c, const Evaluation& from);

 private:
  Evaluation minimizeEffort(const RowsAlongPath& rows, Evaluation e);
  static void countActive(const std::vector<double>& bound, const Eigen::VectorXd& linear,
                          Evaluation& e);
  Eigen::VectorXd gradient(const Eigen::VectorXd& c, const Eigen::VectorXd& theta,
                           const std::vector<double>& bound, const Eigen::VectorXd& linear) const;

  const SosSetup& setup_;
  const FlatOutputMap& flat_;
  const std::vector<PathPoint>& points_;
  const Eigen::VectorXd& reserves_;
  const Eigen::VectorXd& a_min_;
  const int max_slp_;
  const PathEffort* effort_;  // null: the map's linear effort
  PathVariables v_;
};

}  // namespace flatsos::planner::detail
