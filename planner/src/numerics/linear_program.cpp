#include "flatsos/planner/numerics/linear_program.hpp"

#include <stdexcept>

#include "flatsos/plugin/stopwatch.hpp"
#include "numerics/ipopt_support.hpp"

namespace flatsos::planner {

namespace {

using Ipopt::Number;

class LinearProgramTnlp : public Ipopt::TNLP {
 public:
  LinearProgramTnlp(const LinearProgram& lp, const std::optional<Eigen::VectorXd>& start) : lp_(lp), start_(start) {}

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac, Ipopt::Index& nnz_h, IndexStyleEnum& style) override {
    n = static_cast<Ipopt::Index>(lp_.cost.size());
    m = static_cast<Ipopt::Index>(lp_.G.rows());
    nnz_jac = n * m;
    nnz_h = 0;
    style = C_STYLE;
    return true;
  }
  bool get_bounds_info(Ipopt::Index n, Number* xl, Number* xu, Ipopt::Index m, Number* gl, Number* gu) override {
    for (Ipopt::Index i = 0; i < n; ++i) xl[i] = lp_.x_lower[i], xu[i] = lp_.x_upper[i];
    for (Ipopt::Index r = 0; r < m; ++r) gl[r] = lp_.row_lower[r], gu[r] = lp_.row_upper[r];
    return true;
  }
  bool get_starting_point(Ipopt::Index n, bool init_x, Number* x, bool, Number*, Number*, Ipopt::Index, bool, Number*) override {
    if (init_x)
      for (Ipopt::Index i = 0; i < n; ++i) {
        double v = start_ ? (*start_)[i] : 0.0;
        // Inside the bounds: Ipopt would push it anyway, this keeps the start meaningful.
        v = std::min(std::max(v, lp_.x_lower[i]), lp_.x_upper[i]);
        x[i] = v;
      }
    return true;
  }
  bool eval_f(Ipopt::Index n, const Number* x, bool, Number& f) override {
    f = 0.0;
    for (Ipopt::Index i = 0; i < n; ++i) f += lp_.cost[i] * x[i];
    return true;
  }
  bool eval_grad_f(Ipopt::Index n, const Number*, bool, Number* g) override {
    for (Ipopt::Index i = 0; i < n; ++i) g[i] = lp_.cost[i];
    return true;
  }
  bool eval_g(Ipopt::Index n, const Number* x, bool, Ipopt::Index m, Number* g) override {
    const Eigen::Map<const Eigen::VectorXd> xv(x, n);
    Eigen::Map<Eigen::VectorXd>(g, m) = lp_.G * xv;
    return true;
  }
  bool eval_jac_g(Ipopt::Index n, const Number*, bool, Ipopt::Index m, Ipopt::Index, Ipopt::Index* irow, Ipopt::Index* jcol, Number* values) override {
    Ipopt::Index k = 0;
    for (Ipopt::Index r = 0; r < m; ++r)
      for (Ipopt::Index c = 0; c < n; ++c, ++k) {
        if (values) values[k] = lp_.G(r, c);
        else irow[k] = r, jcol[k] = c;
      }
    return true;
  }
  bool eval_h(Ipopt::Index, const Number*, bool, Number, Ipopt::Index, const Number*, bool, Ipopt::Index, Ipopt::Index*, Ipopt::Index*, Number*) override {
    return true;
  }
  void finalize_solution(Ipopt::SolverReturn, Ipopt::Index n, const Number* x, const Number*, const Number*, Ipopt::Index m,
                         const Number*, const Number* lambda, Number obj, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    x_ = Eigen::Map<const Eigen::VectorXd>(x, n);
    lambda_ = Eigen::Map<const Eigen::VectorXd>(lambda, m);
    objective_ = obj;
  }

  Eigen::VectorXd x_, lambda_;
  double objective_ = 0.0;

 private:
  const LinearProgram& lp_;
  const std::optional<Eigen::VectorXd>& start_;
};

}  // namespace

LinearProgramResult solve_linear_program(const LinearProgram& lp, const LinearProgramOptions& o) {
  const Eigen::Index n = lp.cost.size(), m = lp.G.rows();
  if (n == 0) throw std::invalid_argument("linear program: no variables");
  if (lp.G.cols() != n || lp.row_lower.size() != m || lp.row_upper.size() != m || lp.x_lower.size() != n ||
      lp.x_upper.size() != n || (o.start && o.start->size() != n))
    throw std::invalid_argument("linear program: inconsistent sizes");
  if (!lp.cost.allFinite() || !lp.G.allFinite() || lp.row_lower.hasNaN() || lp.row_upper.hasNaN() ||
      lp.x_lower.hasNaN() || lp.x_upper.hasNaN())
    throw std::invalid_argument("linear program: NaN in the data");

  const Stopwatch wall;
  Ipopt::SmartPtr<LinearProgramTnlp> tnlp = new LinearProgramTnlp(lp, o.start);
  auto app = detail::make_ipopt(o.tolerance, o.max_iterations, *tnlp);
  app->Options()->SetStringValue("jac_c_constant", "yes");
  app->Options()->SetStringValue("jac_d_constant", "yes");
  app->Options()->SetStringValue("hessian_constant", "yes");
  app->Options()->SetStringValue("mu_strategy", "adaptive");
  // Constraints are tendon-force reserves in newtons: no relaxation of their bounds (Ipopt's
  // default relaxes by 1e-8 relative, ~1e-6 N here, which showed up as reserve violations).
  app->Options()->SetNumericValue("bound_relax_factor", 0.0);
  app->Options()->SetNumericValue("constr_viol_tol", 1e-9);
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::SmartPtr<Ipopt::TNLP>(GetRawPtr(tnlp)));

  LinearProgramResult r;
  r.solver_status = detail::ipopt_status_name(status);
  r.linear_solver = ipopt_linear_solver_name(app.linear_solver);
  r.status = detail::ipopt_solved(status) ? SolveStatus::Solved
             : detail::ipopt_infeasible(status) ? SolveStatus::Infeasible
                                                 : SolveStatus::Failed;
  r.x = tnlp->x_;
  r.row_multipliers = tnlp->lambda_;
  r.objective = tnlp->objective_;
  if (Ipopt::SmartPtr<Ipopt::SolveStatistics> stats = app->Statistics(); IsValid(stats))
    r.iterations = stats->IterationCount();
  r.wall_seconds = wall.seconds();
  return r;
}

}  // namespace flatsos::planner
