#include "sos/whole_program_nlp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#include "flatsos/planner/numerics/simplex_lp.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "numerics/ipopt_support.hpp"
#include "numerics/lukacs_squares.hpp"
#include "sos/whole_program_start.hpp"

namespace flatsos::planner::detail {

namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

// The proximal rounds (measured on the arm's quartic: without them Ipopt's restoration fails;
// falling a hundredfold per round fails too). Weights are of the factors, which are of order 1.
constexpr double kFirstProximalWeight = 1.0;
constexpr double kProximalFall = 10.0;
constexpr double kLastProximalWeight = 1e-5;
constexpr double kSmallestProximalFall = 1.2;
// The rounds before the last stop at this tolerance and iteration count (a round that takes
// more has met a fold of some certificate and is better tried again with a smaller fall).
constexpr double kRoundTolerance = 1e-7;
constexpr int kRoundIterations = 200;

struct Entry {
  int row, col;
};

bool copy_structure(const std::vector<Entry>& entries, Ipopt::Index* iRow, Ipopt::Index* jCol) {
  for (std::size_t e = 0; e < entries.size(); ++e) {
    iRow[e] = entries[e].row;
    jCol[e] = entries[e].col;
  }
  return true;
}

// s(1 - s) = s - s^2: the coefficient of s^k.
double d_coefficient(int k) { return k == 1 ? 1.0 : k == 2 ? -1.0 : 0.0; }

class WholeProgramNlp : public Ipopt::TNLP {
 public:
  /// Variables: theta (cost.size()), then each block's f and g. Call start_round before a solve.
  WholeProgramNlp(const std::vector<SquaresBlock>& blocks, const VectorXd& cost)
      : blocks_(blocks), cost_(cost), n_theta_(static_cast<int>(cost.size())) {
    for (int j = 0; j < n_theta_; ++j) hess_.push_back({j, j});
    for (const SquaresBlock& b : blocks_) {
      m_ += b.rows();
      const int h = b.half, f0 = b.var_offset, g0 = f0 + h + 1;
      for (int k = 0; k < b.rows(); ++k) {
        const int row = b.con_offset + k;
        for (int j = 0; j < n_theta_; ++j)
          if (b.G(k, j) != 0.0) jac_.push_back({row, j});
        for (int i = 0; i <= h; ++i)
          if (k - i >= 0 && k - i <= h) jac_.push_back({row, f0 + i});
        for (int i = 0; i < h; ++i)
          if (k - i >= 1 && k - i <= h + 1) jac_.push_back({row, g0 + i});
      }
      for (int i = 0; i <= h; ++i)
        for (int j = 0; j <= i; ++j) hess_.push_back({f0 + i, f0 + j});
      for (int i = 0; i < h; ++i)
        for (int j = 0; j <= i; ++j) hess_.push_back({g0 + i, g0 + j});
    }
    n_ = n_theta_ + m_;  // each block has as many factor entries as rows
  }

  /// The next solve starts from x and these multipliers, with (1/2) sum rho_i (x_i - x'_i)^2
  /// added to the cost (rho = 0: none).
  void start_round(const VectorXd& x, const VectorXd& multipliers, const VectorXd& rho) {
    center_ = x;
    lambda_ = multipliers;
    rho_ = rho;
    x_.resize(0);
    multipliers_.resize(0);
  }
  int variables() const { return n_; }
  int equalities() const { return m_; }
  /// Empty until a solve has ended.
  const VectorXd& solution() const { return x_; }
  const VectorXd& multipliers() const { return multipliers_; }

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac, Ipopt::Index& nnz_h,
                    IndexStyleEnum& style) override {
    n = n_;
    m = m_;
    nnz_jac = static_cast<Ipopt::Index>(jac_.size());
    nnz_h = static_cast<Ipopt::Index>(hess_.size());
    style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Ipopt::Index, Ipopt::Number* x_l, Ipopt::Number* x_u, Ipopt::Index, Ipopt::Number* g_l,
                       Ipopt::Number* g_u) override {
    std::fill(x_l, x_l + n_, -2e19);
    std::fill(x_u, x_u + n_, 2e19);
    std::fill(g_l, g_l + m_, 0.0);
    std::fill(g_u, g_u + m_, 0.0);
    return true;
  }

  bool get_starting_point(Ipopt::Index, bool init_x, Ipopt::Number* x, bool, Ipopt::Number*, Ipopt::Number*,
                          Ipopt::Index, bool init_lambda, Ipopt::Number* lambda) override {
    if (init_x) std::copy(center_.data(), center_.data() + n_, x);
    if (init_lambda) std::copy(lambda_.data(), lambda_.data() + m_, lambda);
    return true;  // no bounds: no z to start
  }

  bool eval_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number& f) override {
    f = cost_.dot(Eigen::Map<const VectorXd>(x, n_theta_)) +
        0.5 * (rho_.array() * (Eigen::Map<const VectorXd>(x, n_) - center_).array().square()).sum();
    return true;
  }

  bool eval_grad_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number* grad) override {
    Eigen::Map<VectorXd> gr(grad, n_);
    gr = rho_.cwiseProduct(Eigen::Map<const VectorXd>(x, n_) - center_);
    gr.head(n_theta_) += cost_;
    return true;
  }

  bool eval_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Number* g) override {
    const Eigen::Map<const VectorXd> theta(x, n_theta_);
    for (const SquaresBlock& b : blocks_) {
      const double* f = x + b.var_offset;
      const double* gg = f + b.half + 1;
      for (int k = 0; k < b.rows(); ++k) {
        double v = b.base[k] + b.G.row(k).dot(theta);
        for (int i = std::max(0, k - b.half); i <= std::min(k, b.half); ++i) v -= f[i] * f[k - i];
        for (int i = 0; i < b.half; ++i)
          for (int j = 0; j < b.half; ++j) v -= gg[i] * gg[j] * d_coefficient(k - i - j);
        g[b.con_offset + k] = v;
      }
    }
    return true;
  }

  bool eval_jac_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Index, Ipopt::Index* iRow,
                  Ipopt::Index* jCol, Ipopt::Number* values) override {
    if (values == nullptr) return copy_structure(jac_, iRow, jCol);
    // The same order as the structure: per block and row, theta, then f, then g.
    std::size_t e = 0;
    for (const SquaresBlock& b : blocks_) {
      const double* f = x + b.var_offset;
      const double* gg = f + b.half + 1;
      auto g_at = [&](int i) { return i >= 0 && i < b.half ? gg[i] : 0.0; };
      for (int k = 0; k < b.rows(); ++k) {
        for (int j = 0; j < n_theta_; ++j)
          if (b.G(k, j) != 0.0) values[e++] = b.G(k, j);
        for (int i = 0; i <= b.half; ++i)
          if (k - i >= 0 && k - i <= b.half) values[e++] = -2.0 * f[k - i];
        // d/dg_i of sum_{i,j} g_i g_j d_{k-i-j} = 2 (g_{k-i-1} - g_{k-i-2}).
        for (int i = 0; i < b.half; ++i)
          if (k - i >= 1 && k - i <= b.half + 1) values[e++] = -2.0 * (g_at(k - i - 1) - g_at(k - i - 2));
      }
    }
    return true;
  }

  bool eval_h(Ipopt::Index, const Ipopt::Number*, bool, Ipopt::Number obj_factor, Ipopt::Index, const Ipopt::Number* lambda, bool,
              Ipopt::Index, Ipopt::Index* iRow, Ipopt::Index* jCol, Ipopt::Number* values) override {
    if (values == nullptr) return copy_structure(hess_, iRow, jCol);
    // The cost: linear plus the proximal diagonal; row k holds -f_i f_{k-i} and -g_i g_j d_{k-i-j}.
    std::size_t e = 0;
    for (int j = 0; j < n_theta_; ++j) values[e++] = obj_factor * rho_[j];
    for (const SquaresBlock& b : blocks_) {
      const double* l = lambda + b.con_offset;
      auto l_at = [&](int k) { return k >= 0 && k < b.rows() ? l[k] : 0.0; };
      for (int i = 0; i <= b.half; ++i)
        for (int j = 0; j <= i; ++j)
          values[e++] = -2.0 * l[i + j] + (i == j ? obj_factor * rho_[b.var_offset + i] : 0.0);
      for (int i = 0; i < b.half; ++i)
        for (int j = 0; j <= i; ++j)
          values[e++] = -2.0 * (l_at(i + j + 1) - l_at(i + j + 2)) +
                        (i == j ? obj_factor * rho_[b.var_offset + b.half + 1 + i] : 0.0);
    }
    return true;
  }

  void finalize_solution(Ipopt::SolverReturn, Ipopt::Index n, const Ipopt::Number* x, const Ipopt::Number*,
                         const Ipopt::Number*, Ipopt::Index m, const Ipopt::Number*, const Ipopt::Number* lambda,
                         Ipopt::Number, const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    x_ = Eigen::Map<const VectorXd>(x, n);
    multipliers_ = Eigen::Map<const VectorXd>(lambda, m);
  }

 private:
  const std::vector<SquaresBlock>& blocks_;
  const VectorXd& cost_;
  VectorXd center_, lambda_, rho_, multipliers_;  // center_: the round's start and proximal center
  int n_theta_ = 0, n_ = 0, m_ = 0;
  std::vector<Entry> jac_, hess_;
  VectorXd x_;
};

// The start LP's dual: a weight (N s / N) on one constraint at one point.
}  // namespace

Ipopt::SmartPtr<Ipopt::TNLP> make_whole_program_nlp(const std::vector<SquaresBlock>& blocks, const VectorXd& cost,
                                                    const VectorXd& start, const VectorXd& multipliers,
                                                    const VectorXd& proximal_weights) {
  Ipopt::SmartPtr<WholeProgramNlp> nlp = new WholeProgramNlp(blocks, cost);
  nlp->start_round(start, multipliers, proximal_weights);
  return Ipopt::GetRawPtr(nlp);
}

namespace {

// A vanishing proximal term: rounds with (rho/2) |x - x_last|^2 (theta measured against its
// start's size), each from the last round's point and multipliers, rho falling tenfold per round
// and then to 0. A round that fails is tried again from the same point with a smaller fall (its
// square root), down to kSmallestProximalFall. Empty on success, else why not.
std::string solve_proximal_rounds(WholeProgramNlp& nlp, const SosSettings& o, int n_theta, double theta_scale, VectorXd x,
                                  VectorXd lambda, SosProgramResult& result) {
  const Index n = x.size();
  double rho = kFirstProximalWeight, last_rho = 0.0, fall = kProximalFall;  // last_rho: of the last success
  for (;;) {
    VectorXd weights = VectorXd::Constant(n, rho);
    weights.head(n_theta) /= theta_scale * theta_scale;
    nlp.start_round(x, lambda, weights);
    const double tol = rho == 0.0 ? o.whole_program.tolerance : kRoundTolerance;
    const int budget = o.whole_program.max_iterations - result.ipopt_iterations;
    const IpoptSession app = make_ipopt(tol, rho == 0.0 ? budget : std::min(budget, kRoundIterations), nlp);
    app->Options()->SetNumericValue("constr_viol_tol", tol);
    app->Options()->SetNumericValue("acceptable_tol", tol);
    app->Options()->SetNumericValue("acceptable_constr_viol_tol", tol);
    app->Options()->SetStringValue("warm_start_init_point", "yes");
    const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(&nlp);
    result.ipopt_calls += 1;
    if (Ipopt::IsValid(app->Statistics())) result.ipopt_iterations += app->Statistics()->IterationCount();
    add_linear_solver_name(result.ipopt_linear_solver, ipopt_linear_solver_name(app.linear_solver));
    const bool solved = (status == Ipopt::Solve_Succeeded || (rho > 0.0 && ipopt_solved(status))) &&
                        nlp.solution().size() == n && nlp.multipliers().size() == nlp.equalities();
    if (solved && rho == 0.0) return {};
    if (solved) {
      x = nlp.solution();
      lambda = nlp.multipliers();
      last_rho = rho;
      fall = std::min(kProximalFall, fall * fall);  // back to faster falls once a round succeeds
    } else {
      fall = std::sqrt(fall);
      if (last_rho == 0.0 || fall < kSmallestProximalFall || result.ipopt_iterations >= o.whole_program.max_iterations)
        return "the whole-program NLP stopped without an optimum: Ipopt " + ipopt_status_name(status) +
               " at proximal weight " + std::to_string(rho);
    }
    // Below the last weight the next round is the problem itself, unless a round just failed.
    rho = solved && last_rho / fall < kLastProximalWeight ? 0.0 : last_rho / fall;
  }
}

}  // namespace

bool solve_whole_program(const SosSetup& setup, const SosSettings& o, VectorXd& theta, SosProgramResult& result) {
  const Stopwatch solve;
  auto fail = [&](SolveStatus status, std::string message) {
    result.status = status;
    result.message = std::move(message);
    result.solve_seconds = solve.seconds();
    return false;
  };
  if (const std::string reason = fixed_violation(setup, o.feasibility_margin_N); !reason.empty())
    return fail(SolveStatus::Infeasible, reason);
  if (const std::string reason = fixed_data_violation(setup); !reason.empty()) return fail(SolveStatus::Infeasible, reason);
  if (setup.free_coefficients == 0) {  // the equalities fix Y, and every constraint holds
    theta = VectorXd();
    result.certified = true;
    result.solve_seconds = solve.seconds();
    return true;
  }
  if (std::none_of(setup.constraints.begin(), setup.constraints.end(), moves_with_theta))
    return fail(SolveStatus::Failed, "no constraint depends on the free coefficients, so the whole-program NLP "
                                     "has nothing to bound its linear cost (the exchange bounds them by a box)");
  std::string why;
  VectorXd theta_start;
  std::vector<StartDual> duals;
  if (!strictly_feasible_start(setup, o, theta_start, duals, why)) return fail(SolveStatus::Failed, why);

  const int n_theta = setup.free_coefficients;
  const WholeProgramStart start = blocks_from(setup, theta_start);
  Ipopt::SmartPtr<WholeProgramNlp> nlp = new WholeProgramNlp(start.blocks, setup.lp.cost);
  result.nlp_variables = nlp->variables();
  result.nlp_equalities = nlp->equalities();
  const double theta_scale = std::max(1.0, theta_start.cwiseAbs().maxCoeff());
  const VectorXd x0 = Eigen::Map<const VectorXd>(start.x.data(), static_cast<Index>(start.x.size()));
  if (std::string failure = solve_proximal_rounds(*nlp, o, n_theta, theta_scale, x0, start_multipliers(start, duals), result);
      !failure.empty())
    return fail(SolveStatus::Failed, std::move(failure));
  theta = nlp->solution().head(n_theta);
  record_certificates(setup, start.blocks, nlp->solution(), theta, result);
  result.solve_seconds = solve.seconds();
  if (!result.certified) {
    std::ostringstream msg;
    msg << "the whole-program NLP's certificates leave a residual of " << result.max_certificate_residual_N
        << " N (allowed " << kConstraintTolerance_N << " N)";
    result.status = SolveStatus::Failed;
    result.message = msg.str();
    return false;
  }
  return true;
}

}  // namespace flatsos::planner::detail

