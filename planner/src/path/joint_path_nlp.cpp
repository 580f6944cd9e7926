#include "path/joint_path_nlp.hpp"

#include <cmath>
#include <utility>

#include "numerics/ipopt_support.hpp"

namespace flatsos::planner::detail {

namespace {

constexpr double kInverseCurvatureFloor = 1e-3;

using Ipopt::Number;

// Y_l >= 0 at a point: the flat output's basis row over its free coefficients.
struct LinearRow {
  std::vector<int> columns;
  std::vector<double> values;
  double lower = 0.0;
};

std::vector<LinearRow> flat_output_rows(const SosSetup& setup, const std::vector<PathPoint>& points) {
  std::vector<LinearRow> out;
  for (const OutputParameterization& y : setup.outputs)
    for (const PathPoint& pt : points) {
      const Eigen::RowVectorXd b = setup.basis.derivativeRow(pt.flat.t_s, 0);
      LinearRow row;
      row.lower = -b.dot(y.particular);
      const Eigen::RowVectorXd slope = b * y.nullspace;
      for (Eigen::Index k = 0; k < slope.size(); ++k)
        if (slope[k] != 0.0) row.columns.push_back(y.offset + static_cast<int>(k)), row.values.push_back(slope[k]);
      out.push_back(std::move(row));
    }
  return out;
}

class JointPathNlp : public Ipopt::TNLP {
 public:
  JointPathNlp(const SosSetup& setup, const PathVariables& v, const PathRows& rows, std::vector<LinearRow> linear,
               JointPathNlpPoint start)
      : setup_(setup), v_(v), rows_(rows), linear_(std::move(linear)), at_(std::move(start)) {
    for (const auto& t : rows_(at_.z, true).jacobian) jacobian_pattern_.emplace_back(t.row(), t.col());
    for (const auto& t : rows_.hessianPattern()) hessian_pattern_.emplace_back(t.row(), t.col());
  }

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac, Ipopt::Index& nnz_h, IndexStyleEnum& style) override {
    n = v_.size();
    m = static_cast<Ipopt::Index>(linear_.size()) + rows_.rows();
    nnz_jac = static_cast<Ipopt::Index>(jacobian_pattern_.size());
    for (const auto& r : linear_) nnz_jac += static_cast<Ipopt::Index>(r.columns.size());
    nnz_h = static_cast<Ipopt::Index>(hessian_pattern_.size());
    style = C_STYLE;
    return true;
  }
  bool get_bounds_info(Ipopt::Index n, Number* xl, Number* xu, Ipopt::Index m, Number* gl, Number* gu) override {
    for (Ipopt::Index i = 0; i < n; ++i) {
      const bool theta = i < v_.thetas;
      xl[i] = theta ? setup_.lp.x_lower[i] : -1e19;
      xu[i] = theta ? setup_.lp.x_upper[i] : 1e19;
    }
    for (Ipopt::Index r = 0; r < m; ++r) {
      const auto linear = static_cast<std::size_t>(r);
      gl[r] = linear < linear_.size() ? linear_[linear].lower : 0.0;
      gu[r] = 1e19;
    }
    return true;
  }
  bool get_starting_point(Ipopt::Index n, bool init_x, Number* x, bool init_z, Number* z_L, Number* z_U, Ipopt::Index m, bool init_lambda,
                          Number* lambda) override {
    if (init_x) Eigen::Map<Eigen::VectorXd>(x, n) = at_.z;
    if (init_z) {
      Eigen::Map<Eigen::VectorXd>(z_L, n) = at_.z_lower;
      Eigen::Map<Eigen::VectorXd>(z_U, n) = at_.z_upper;
    }
    if (init_lambda) Eigen::Map<Eigen::VectorXd>(lambda, m) = at_.rows;
    return true;
  }
  bool eval_f(Ipopt::Index n, const Number* x, bool, Number& f) override {
    f = setup_.cost_constant + setup_.lp.cost.dot(Eigen::Map<const Eigen::VectorXd>(x, n).head(v_.thetas));
    return true;
  }
  bool eval_grad_f(Ipopt::Index n, const Number*, bool, Number* g) override {
    Eigen::Map<Eigen::VectorXd> grad(g, n);
    grad.setZero();
    grad.head(v_.thetas) = setup_.lp.cost;
    return true;
  }
  bool eval_g(Ipopt::Index n, const Number* x, bool, Ipopt::Index, Number* g) override {
    const Eigen::Map<const Eigen::VectorXd> z(x, n);
    Ipopt::Index r = 0;
    for (const auto& row : linear_) {
      double s = 0.0;
      for (std::size_t k = 0; k < row.columns.size(); ++k) s += row.values[k] * z[row.columns[k]];
      g[r++] = s;
    }
    rows_.evaluateInto(z, g + r, nullptr);
    return true;
  }
  bool eval_jac_g(Ipopt::Index n, const Number* x, bool, Ipopt::Index, Ipopt::Index, Ipopt::Index* irow, Ipopt::Index* jcol, Number* values) override {
    Ipopt::Index k = 0;
    const auto linear_rows = static_cast<Ipopt::Index>(linear_.size());
    if (!values) {
      for (Ipopt::Index r = 0; r < linear_rows; ++r)
        for (int c : linear_[static_cast<std::size_t>(r)].columns) irow[k] = r, jcol[k++] = c;
      for (const auto& [r, c] : jacobian_pattern_) irow[k] = linear_rows + r, jcol[k++] = c;
      return true;
    }
    for (const auto& row : linear_)
      for (double v : row.values) values[k++] = v;
    row_values_.resize(static_cast<std::size_t>(rows_.rows()));
    rows_.evaluateInto(Eigen::Map<const Eigen::VectorXd>(x, n), row_values_.data(), values + k);
    return true;
  }
  bool eval_h(Ipopt::Index n, const Number* x, bool, Number, Ipopt::Index, const Number* lambda, bool, Ipopt::Index, Ipopt::Index* irow, Ipopt::Index* jcol,
              Number* values) override {
    if (!values) {
      Ipopt::Index k = 0;
      for (const auto& [r, c] : hessian_pattern_) irow[k] = r, jcol[k++] = c;
      return true;
    }
    // The cost and the linear rows have no curvature.
    rows_.lagrangianHessianInto(Eigen::Map<const Eigen::VectorXd>(x, n), lambda + linear_.size(), values);
    return true;
  }
  void finalize_solution(Ipopt::SolverReturn, Ipopt::Index n, const Number* x, const Number* z_L, const Number* z_U, Ipopt::Index m,
                         const Number*, const Number* lambda, Number, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    at_.z = Eigen::Map<const Eigen::VectorXd>(x, n);
    at_.z_lower = Eigen::Map<const Eigen::VectorXd>(z_L, n);
    at_.z_upper = Eigen::Map<const Eigen::VectorXd>(z_U, n);
    at_.rows = Eigen::Map<const Eigen::VectorXd>(lambda, m);
  }

  const JointPathNlpPoint& at() const { return at_; }

 private:
  const SosSetup& setup_;
  const PathVariables& v_;
  const PathRows& rows_;
  std::vector<LinearRow> linear_;
  JointPathNlpPoint at_;
  std::vector<std::pair<int, int>> jacobian_pattern_, hessian_pattern_;
  std::vector<double> row_values_;  // eval_jac_g's rows, computed alongside their Jacobian
};

// The last round's row multipliers laid out for `count` points, of which the first `known` are
// the last round's (the new points' rows start at 0).
Eigen::VectorXd extend_row_multipliers(const Eigen::VectorXd& last, int outputs, int rows_per_point, std::size_t known,
                                       std::size_t count) {
  const auto k = static_cast<Eigen::Index>(known), c = static_cast<Eigen::Index>(count);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(outputs * c + rows_per_point * c);
  for (int l = 0; l < outputs; ++l) out.segment(l * c, k) = last.segment(l * k, k);
  out.segment(outputs * c, rows_per_point * k) = last.segment(outputs * k, rows_per_point * k);
  return out;
}

}  // namespace

JointPathNlpOutcome solve_joint_path_nlp(const SosSetup& setup, const FlatOutputMap& flat, const PathVariables& v,
                                         const std::vector<PathPoint>& points, const Eigen::VectorXd& reserves_N,
                                         const Eigen::VectorXd& a_min, const JointPathNlpPoint& start,
                                         std::size_t start_points, double tolerance, int max_iterations) {
  // Newton steps with the torque jet linearized: nearly as few iterations at a fraction of the
  // Hessian's cost (TorqueCurvature::Linearized). The muscles whose bound rows carry at most
  // kInverseCurvatureFloor of the largest multiplier add no inverse curvature either: on the
  // arm's free path the same 86 iterations to the same plan, the path stage about 13 % faster
  // (1e-2: 89 iterations, 1e-1: 92; docs/method/free_path.md, "Speed").
  const PathRows rows(flat, v, points, reserves_N, a_min, TorqueCurvature::Linearized, kInverseCurvatureFloor);
  JointPathNlpPoint first = start;
  const bool warm = start.hasMultipliers();
  if (warm)
    first.rows = extend_row_multipliers(start.rows, static_cast<int>(setup.outputs.size()),
                                        flat.numMuscles() * PathRows::kRows, start_points, points.size());
  Ipopt::SmartPtr<JointPathNlp> nlp = new JointPathNlp(setup, v, rows, flat_output_rows(setup, points), std::move(first));
  auto app = make_ipopt(tolerance, max_iterations, *nlp);
  app->Options()->SetNumericValue("bound_relax_factor", 0.0);
  app->Options()->SetNumericValue("constr_viol_tol", 1e-9);
  // The effort in N s is O(100-1000): scaled to O(1).
  app->Options()->SetNumericValue("obj_scaling_factor",
                                  1.0 / (1.0 + std::abs(setup.cost_constant + setup.lp.cost.dot(start.z.head(v.thetas)))));
  // The start is a plan whose active rows are at their bounds. Ipopt's default barrier (mu = 0.1)
  // moved it far away, to a worse local optimum (254 against 205 N s on the arm). A small
  // barrier keeps it near. The rows' slacks start 1e-2 off their bounds: with a push of 1e-6
  // the first dozen iterations only crept away from the start's active rows (steps growing
  // about twofold per iteration). A later round starts from the last round's primal-dual
  // optimum, its slacks again pushed off their bounds (3e-2) and every multiplier at least 1e-3:
  // the new points' rows start violated, and with the last optimum's active slacks at 1e-9 the
  // first 15-20 steps were cut to 1e-6..1e-2 of their length by the fraction to the boundary.
  // On the arm's free path 81 -> 59 iterations, on seven configurations 796 -> 596, each to the
  // same plan (docs/method/free_path.md, "Speed").
  app->Options()->SetNumericValue("mu_init", warm ? 1e-7 : 1e-5);
  app->Options()->SetNumericValue("bound_push", 1e-6);
  app->Options()->SetNumericValue("bound_frac", 1e-6);
  app->Options()->SetNumericValue("slack_bound_push", 1e-2);
  app->Options()->SetNumericValue("slack_bound_frac", 1e-2);
  if (warm) {
    app->Options()->SetStringValue("warm_start_init_point", "yes");
    app->Options()->SetNumericValue("warm_start_bound_push", 1e-9);
    app->Options()->SetNumericValue("warm_start_bound_frac", 1e-9);
    app->Options()->SetNumericValue("warm_start_slack_bound_push", 3e-2);
    app->Options()->SetNumericValue("warm_start_slack_bound_frac", 3e-2);
    app->Options()->SetNumericValue("warm_start_mult_bound_push", 1e-3);
  }
  // The KKT system is an arrow: thousands of rows, each coupling a slack and a multiplier to the
  // few dozen variables of its point, around a dense block of the path's coefficients. By default
  // the rows are eliminated first and the variables' dense Schur complement factored (the
  // condensed dense LDL^T: a few milliseconds per iteration). When MUMPS serves it instead, its
  // automatic ordering (nested dissection) took about 300 ms per factorization at 180 points;
  // approximate minimum fill eliminates the rows first: 14.1 s instead of 18.7 s on the arm's
  // free path (docs/method/free_path.md, "Speed").
  if (app.linear_solver == IpoptLinearSolver::Mumps) app->Options()->SetIntegerValue("mumps_pivot_order", 2);
  // Ipopt refines every search direction at least once by default, which costs a residual over
  // the whole Jacobian and another solve. The dense LDL^T's directions need none (their backward
  // error is near rounding, docs/method/ipopt_linear_solver.md); Ipopt still refines a direction
  // whose residual is large. The same iterations, the path stage about 6 % faster on the arm.
  if (app.linear_solver == IpoptLinearSolver::DenseLdlt) app->Options()->SetIntegerValue("min_refinement_steps", 0);
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::SmartPtr<Ipopt::TNLP>(GetRawPtr(nlp)));
  JointPathNlpOutcome out;
  out.solved = ipopt_solved(status);
  out.infeasible = ipopt_infeasible(status);
  out.solver_status = ipopt_status_name(status);
  out.linear_solver = ipopt_linear_solver_name(app.linear_solver);
  out.at = nlp->at();
  if (Ipopt::SmartPtr<Ipopt::SolveStatistics> stats = app->Statistics(); IsValid(stats)) out.iterations = stats->IterationCount();
  return out;
}

}  // namespace flatsos::planner::detail
