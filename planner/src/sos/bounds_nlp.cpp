#include "sos/bounds_nlp.hpp"

#include "numerics/ipopt_support.hpp"

namespace flatsos::planner::detail {

namespace {

using Ipopt::Number;

class BoundedSopNlp : public Ipopt::TNLP {
 public:
  BoundedSopNlp(const SosSetup& setup, const FlatOutputMap& flat, const std::vector<BoundPoint>& points,
                const Eigen::VectorXd& a_min, const Eigen::VectorXd& start)
      : setup_(setup), flat_(flat), points_(points), a_min_(a_min), start_(start) {
    const Eigen::MatrixXd& G = setup_.lp.G;
    for (Eigen::Index r = 0; r < G.rows(); ++r)
      for (Eigen::Index c = 0; c < G.cols(); ++c)
        if (G(r, c) != 0.0) linear_.push_back({static_cast<Ipopt::Index>(r), static_cast<Ipopt::Index>(c)});
  }

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac, Ipopt::Index& nnz_h, IndexStyleEnum& style) override {
    n = setup_.free_coefficients;
    m = static_cast<Ipopt::Index>(setup_.lp.G.rows() + kRowsPerMuscle * points_.size() * muscles());
    nnz_jac = static_cast<Ipopt::Index>(linear_.size());
    for (const auto& bp : points_) nnz_jac += static_cast<Ipopt::Index>(kRowsPerMuscle * muscles() * bp.columns.size());
    nnz_h = 0;
    style = C_STYLE;
    return true;
  }
  bool get_bounds_info(Ipopt::Index n, Number* xl, Number* xu, Ipopt::Index, Number* gl, Number* gu) override {
    for (Ipopt::Index i = 0; i < n; ++i) xl[i] = setup_.lp.x_lower[i], xu[i] = setup_.lp.x_upper[i];
    Ipopt::Index r = 0;
    for (; r < setup_.lp.G.rows(); ++r) gl[r] = setup_.lp.row_lower[r], gu[r] = 1e19;
    for (std::size_t i = 0; i < points_.size(); ++i)
      for (int j = 0; j < muscles(); ++j) {
        for (int k = 0; k < kRowsPerMuscle; ++k) gl[r] = 0.0, gu[r++] = 1e19;
      }
    return true;
  }
  bool get_starting_point(Ipopt::Index n, bool init_x, Number* x, bool, Number*, Number*, Ipopt::Index, bool, Number*) override {
    if (init_x)
      for (Ipopt::Index i = 0; i < n; ++i) x[i] = start_[i];
    return true;
  }
  bool eval_f(Ipopt::Index n, const Number* x, bool, Number& f) override {
    f = setup_.lp.cost.dot(Eigen::Map<const Eigen::VectorXd>(x, n));
    return true;
  }
  bool eval_grad_f(Ipopt::Index n, const Number*, bool, Number* g) override {
    Eigen::Map<Eigen::VectorXd>(g, n) = setup_.lp.cost;
    return true;
  }
  bool eval_g(Ipopt::Index n, const Number* x, bool, Ipopt::Index, Number* g) override {
    const Eigen::Map<const Eigen::VectorXd> theta(x, n);
    const Eigen::Index linear_rows = setup_.lp.G.rows();
    Eigen::Map<Eigen::VectorXd>(g, linear_rows) = setup_.lp.G * theta;
    Ipopt::Index r = static_cast<Ipopt::Index>(linear_rows);
    for (const auto& bp : points_)
      for (int j = 0; j < muscles(); ++j) {
        const MuscleBoundRows rows = bound_rows(flat_, bp, j, a_min_[j], theta, false);
        for (double v : rows.value) g[r++] = v;
      }
    return true;
  }
  bool eval_jac_g(Ipopt::Index n, const Number* x, bool, Ipopt::Index, Ipopt::Index, Ipopt::Index* irow, Ipopt::Index* jcol, Number* values) override {
    Ipopt::Index k = 0;
    if (!values) {
      for (const auto& [r, c] : linear_) irow[k] = r, jcol[k++] = c;
      Ipopt::Index r = static_cast<Ipopt::Index>(setup_.lp.G.rows());
      for (const auto& bp : points_)
        for (int j = 0; j < muscles(); ++j, r += kRowsPerMuscle)
          for (int which = 0; which < kRowsPerMuscle; ++which)
            for (int c : bp.columns) irow[k] = r + which, jcol[k++] = c;
      return true;
    }
    const Eigen::Map<const Eigen::VectorXd> theta(x, n);
    for (const auto& [r, c] : linear_) values[k++] = setup_.lp.G(r, c);
    for (const auto& bp : points_)
      for (int j = 0; j < muscles(); ++j) {
        const MuscleBoundRows rows = bound_rows(flat_, bp, j, a_min_[j], theta, true);
        for (const auto& grad : rows.gradient)
          for (std::size_t c = 0; c < bp.columns.size(); ++c) values[k++] = column_derivative(bp, grad, j, c);
      }
    return true;
  }
  bool eval_h(Ipopt::Index, const Number*, bool, Number, Ipopt::Index, const Number*, bool, Ipopt::Index, Ipopt::Index*, Ipopt::Index*, Number*) override {
    return false;  // limited-memory quasi-Newton
  }
  void finalize_solution(Ipopt::SolverReturn, Ipopt::Index n, const Number* x, const Number*, const Number*, Ipopt::Index,
                         const Number*, const Number*, Number, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    x_ = Eigen::Map<const Eigen::VectorXd>(x, n);
  }

  Eigen::VectorXd x_;

 private:
  int muscles() const { return flat_.numMuscles(); }

  const SosSetup& setup_;
  const FlatOutputMap& flat_;
  const std::vector<BoundPoint>& points_;
  const Eigen::VectorXd& a_min_;
  const Eigen::VectorXd& start_;
  std::vector<std::pair<Ipopt::Index, Ipopt::Index>> linear_;
};

}  // namespace

IpoptBoundsOutcome solve_bounds_by_ipopt(const SosSetup& setup, const FlatOutputMap& flat,
                                         const std::vector<BoundPoint>& points, const Eigen::VectorXd& a_min,
                                         const Eigen::VectorXd& start, int max_iterations) {
  Ipopt::SmartPtr<BoundedSopNlp> nlp = new BoundedSopNlp(setup, flat, points, a_min, start);
  auto app = make_ipopt(1e-8, max_iterations, *nlp);
  app->Options()->SetStringValue("hessian_approximation", "limited-memory");
  app->Options()->SetStringValue("mu_strategy", "adaptive");
  app->Options()->SetNumericValue("bound_relax_factor", 0.0);
  app->Options()->SetNumericValue("constr_viol_tol", 1e-9);
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::SmartPtr<Ipopt::TNLP>(GetRawPtr(nlp)));
  IpoptBoundsOutcome out;
  out.solved = ipopt_solved(status);
  out.infeasible = ipopt_infeasible(status);
  out.solver_status = ipopt_status_name(status);
  out.linear_solver = ipopt_linear_solver_name(app.linear_solver);
  out.x = nlp->x_;
  if (Ipopt::SmartPtr<Ipopt::SolveStatistics> stats = app->Statistics(); IsValid(stats)) out.iterations = stats->IterationCount();
  return out;
}

}  // namespace flatsos::planner::detail
