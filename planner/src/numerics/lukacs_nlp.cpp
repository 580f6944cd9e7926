#include "numerics/lukacs_nlp.hpp"

#include <cmath>
#include <cstdarg>
#include <cstdio>

#include "numerics/ipopt_support.hpp"

namespace flatsos::planner::detail {

namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

struct JacEntry {
  int row, col;
  int block, gram, k, i, c;
};
struct HessEntry {
  int row, col;
  int block, gram, i, j;  // variables (i, c) and (j, c) of the same column c, i >= j
};

class LukacsNlp : public Ipopt::TNLP {
 public:
  LukacsNlp(std::vector<Block>& blocks, FactorLayout layout, double proximal_weight,
            bool nonneg_diag)
      : blocks_(blocks), layout_(layout), w_(proximal_weight), nonneg_diag_(nonneg_diag) {
    for (Block& b : blocks_) {
      b.var_offset = n_;
      b.con_offset = m_;
      n_ += layout_.size(b.op.m0) + layout_.size(b.op.m1);
      m_ += b.op.degree + 1;
      b.start.clear();
      layout_.pack(b.start_L0, b.start);
      layout_.pack(b.start_L1, b.start);
    }
    for (std::size_t bi = 0; bi < blocks_.size(); ++bi) {
      const Block& b = blocks_[bi];
      for (int g = 0; g < 2; ++g) {
        const int m = g == 0 ? b.op.m0 : b.op.m1;
        const std::vector<MatrixXd>& A = g == 0 ? b.op.A0 : b.op.A1;
        const int goff = gram_offset(b, g);
        // g_k = sum_c sum_{i,j} A_k(i,j) L(i,c) L(j,c) (A_k symmetric), so
        // d g_k / d L(i,c) = 2 sum_j A_k(i,j) L(j,c): structurally nonzero iff some A_k(i,j) != 0
        // with row j present in column c.
        for (int k = 0; k <= b.op.degree; ++k)
          for (int c = 0; c < m; ++c)
            for (int i = layout_.first_row(c); i < m; ++i) {
              bool nz = false;
              for (int j = layout_.first_row(c); j < m && !nz; ++j)
                nz = A[static_cast<std::size_t>(k)](i, j) != 0.0;
              if (nz)
                jac_.push_back({b.con_offset + k, goff + layout_.index(m, i, c),
                                static_cast<int>(bi), g, k, i, c});
            }
        // d2 g_k / d L(i,c) d L(j,c') = 2 A_k(i,j) if c == c', else 0. Lower triangle: i >= j.
        for (int c = 0; c < m; ++c)
          for (int i = layout_.first_row(c); i < m; ++i)
            for (int j = layout_.first_row(c); j <= i; ++j) {
              bool nz = (i == j);
              for (int k = 0; k <= b.op.degree && !nz; ++k)
                nz = A[static_cast<std::size_t>(k)](i, j) != 0.0;
              if (nz)
                hess_.push_back({goff + layout_.index(m, i, c), goff + layout_.index(m, j, c),
                                 static_cast<int>(bi), g, i, j});
            }
      }
    }
  }

  int num_variables() const { return n_; }
  int num_constraints() const { return m_; }
  const std::vector<double>& solution() const { return x_; }

  int gram_offset(const Block& b, int gram) const {
    return b.var_offset + (gram == 0 ? 0 : layout_.size(b.op.m0));
  }

  /// The factor `gram` (0 or 1) of block b from Ipopt's variables.
  MatrixXd unpack(const double* x, const Block& b, int gram) const {
    const int m = gram == 0 ? b.op.m0 : b.op.m1;
    const int goff = gram_offset(b, gram);
    MatrixXd L = MatrixXd::Zero(m, m);
    for (int c = 0; c < m; ++c)
      for (int i = layout_.first_row(c); i < m; ++i) L(i, c) = x[goff + layout_.index(m, i, c)];
    return L;
  }

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac, Ipopt::Index& nnz_h,
                    IndexStyleEnum& style) override {
    n = n_;
    m = m_;
    nnz_jac = static_cast<Ipopt::Index>(jac_.size());
    nnz_h = static_cast<Ipopt::Index>(hess_.size());
    style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Ipopt::Index, Ipopt::Number* x_l, Ipopt::Number* x_u, Ipopt::Index,
                       Ipopt::Number* g_l, Ipopt::Number* g_u) override {
    for (int v = 0; v < n_; ++v) {
      x_l[v] = -2e19;
      x_u[v] = 2e19;
    }
    if (nonneg_diag_)
      for (const Block& b : blocks_)
        for (int g = 0; g < 2; ++g) {
          const int m = g == 0 ? b.op.m0 : b.op.m1;
          for (int c = 0; c < m; ++c) x_l[gram_offset(b, g) + layout_.index(m, c, c)] = 0.0;
        }
    for (int r = 0; r < m_; ++r) g_l[r] = g_u[r] = 0.0;
    return true;
  }

  bool get_starting_point(Ipopt::Index, bool init_x, Ipopt::Number* x, bool init_z, Ipopt::Number*,
                          Ipopt::Number*, Ipopt::Index, bool init_lambda, Ipopt::Number*) override {
    if (init_z || init_lambda) return false;
    if (init_x)
      for (const Block& b : blocks_) std::copy(b.start.begin(), b.start.end(), x + b.var_offset);
    return true;
  }

  bool eval_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number& f) override {
    f = 0.0;
    if (w_ > 0.0)
      for (const Block& b : blocks_)
        for (std::size_t v = 0; v < b.start.size(); ++v) {
          const double e = x[b.var_offset + static_cast<int>(v)] - b.start[v];
          f += 0.5 * w_ * e * e;
        }
    return true;
  }

  bool eval_grad_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number* grad) override {
    for (const Block& b : blocks_)
      for (std::size_t v = 0; v < b.start.size(); ++v) {
        const int xv = b.var_offset + static_cast<int>(v);
        grad[xv] = w_ * (x[xv] - b.start[v]);
      }
    return true;
  }

  bool eval_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Number* g) override {
    for (const Block& b : blocks_) {
      const MatrixXd L0 = unpack(x, b, 0), L1 = unpack(x, b, 1);
      const VectorXd r = apply_operator(b.op, L0 * L0.transpose(), L1 * L1.transpose()) - b.target;
      for (Index k = 0; k < r.size(); ++k) g[b.con_offset + k] = b.weight * r[k];
    }
    return true;
  }

  bool eval_jac_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Index,
                  Ipopt::Index* iRow, Ipopt::Index* jCol, Ipopt::Number* values) override {
    if (values == nullptr) {
      for (std::size_t e = 0; e < jac_.size(); ++e) {
        iRow[e] = jac_[e].row;
        jCol[e] = jac_[e].col;
      }
      return true;
    }
    int cached = -1;  // entries are grouped by block: unpack each block's factors once
    MatrixXd L[2];
    for (std::size_t e = 0; e < jac_.size(); ++e) {
      const JacEntry& je = jac_[e];
      const Block& b = blocks_[static_cast<std::size_t>(je.block)];
      if (je.block != cached) {
        cached = je.block;
        L[0] = unpack(x, b, 0);
        L[1] = unpack(x, b, 1);
      }
      const MatrixXd& A = (je.gram == 0 ? b.op.A0 : b.op.A1)[static_cast<std::size_t>(je.k)];
      values[e] = 2.0 * b.weight * A.row(je.i).dot(L[je.gram].col(je.c));
    }
    return true;
  }

  bool eval_h(Ipopt::Index, const Ipopt::Number*, bool, Ipopt::Number obj_factor, Ipopt::Index,
              const Ipopt::Number* lambda, bool, Ipopt::Index, Ipopt::Index* iRow,
              Ipopt::Index* jCol, Ipopt::Number* values) override {
    if (values == nullptr) {
      for (std::size_t e = 0; e < hess_.size(); ++e) {
        iRow[e] = hess_[e].row;
        jCol[e] = hess_[e].col;
      }
      return true;
    }
    for (std::size_t e = 0; e < hess_.size(); ++e) {
      const HessEntry& he = hess_[e];
      const Block& b = blocks_[static_cast<std::size_t>(he.block)];
      const std::vector<MatrixXd>& A = he.gram == 0 ? b.op.A0 : b.op.A1;
      double v = 0.0;
      for (int k = 0; k <= b.op.degree; ++k)
        v += lambda[b.con_offset + k] * A[static_cast<std::size_t>(k)](he.i, he.j);
      v *= 2.0 * b.weight;
      if (he.row == he.col) v += obj_factor * w_;
      values[e] = v;
    }
    return true;
  }

  void finalize_solution(Ipopt::SolverReturn, Ipopt::Index n, const Ipopt::Number* x,
                         const Ipopt::Number*, const Ipopt::Number*, Ipopt::Index,
                         const Ipopt::Number*, const Ipopt::Number*, Ipopt::Number,
                         const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    x_.assign(x, x + n);
  }

 private:
  std::vector<Block>& blocks_;
  FactorLayout layout_;
  double w_;
  bool nonneg_diag_;
  int n_ = 0, m_ = 0;
  std::vector<JacEntry> jac_;
  std::vector<HessEntry> hess_;
  std::vector<double> x_;
};

// Collects Ipopt's output (used for the derivative checker's report only).
class StringJournal : public Ipopt::Journal {
 public:
  StringJournal() : Ipopt::Journal("flatsos_string", Ipopt::J_SUMMARY) {}
  std::string text;

 protected:
  void PrintImpl(Ipopt::EJournalCategory, Ipopt::EJournalLevel, const char* str) override {
    text += str;
  }
  void PrintfImpl(Ipopt::EJournalCategory, Ipopt::EJournalLevel, const char* pformat,
                  va_list ap) override {
    char buf[4096];
    std::vsnprintf(buf, sizeof buf, pformat, ap);
    text += buf;
  }
  void FlushBufferImpl() override {}
};

}  // namespace

// One Ipopt call on all the blocks.
IpoptRun run_ipopt(std::vector<Block>& blocks, FactorLayout layout,
                   const CertificationStudyOptions& options, double tol, bool derivative_test) {
  IpoptRun run;
  Ipopt::SmartPtr<LukacsNlp> nlp =
      new LukacsNlp(blocks, layout, options.proximal_weight, options.nonnegative_diagonal);
  run.variables = nlp->num_variables();
  run.constraints = nlp->num_constraints();
  // With the block weights, a constraint violation tau means a relative monomial residual
  // <= tau; ask Ipopt for a tenth of the certification tolerance (re-checked by the caller).
  const double ipopt_tol = std::min(1e-8, 0.1 * tol);
  const detail::IpoptSession app = detail::make_ipopt(ipopt_tol, options.max_iterations, *nlp);
  app->Options()->SetNumericValue("constr_viol_tol", ipopt_tol);
  // No early "acceptable" exit: at polynomials with exact zeros the solution is singular and
  // Newton converges linearly; Ipopt would otherwise stop there short of the tolerance.
  app->Options()->SetNumericValue("acceptable_tol", ipopt_tol);
  app->Options()->SetNumericValue("acceptable_constr_viol_tol", ipopt_tol);
  app->Options()->SetStringValue("nlp_scaling_method", "none");  // blocks are normalized
  if (options.ipopt_print_level > 0)
    app->Options()->SetIntegerValue("print_level", options.ipopt_print_level);
  Ipopt::SmartPtr<StringJournal> journal;
  if (derivative_test) {
    app->Options()->SetStringValue("derivative_test", "second-order");
    app->Options()->SetNumericValue("point_perturbation_radius", 0.5);
    journal = new StringJournal();
    journal->SetAllPrintLevels(Ipopt::J_SUMMARY);
    app->Jnlst()->AddJournal(Ipopt::GetRawPtr(journal));
  }
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::GetRawPtr(nlp));
  run.status = detail::ipopt_status_name(status);
  run.linear_solver = ipopt_linear_solver_name(app.linear_solver);
  if (Ipopt::IsValid(app->Statistics())) run.iterations = app->Statistics()->IterationCount();
  if (derivative_test) {
    run.derivative_report = journal->text;
    const std::string& t = journal->text;
    if (t.find("No errors detected by derivative checker") != std::string::npos) {
      run.derivative_errors = 0;
    } else {
      const std::string key = "Derivative checker detected ";
      const auto pos = t.find(key);
      if (pos != std::string::npos) run.derivative_errors = std::atoi(t.c_str() + pos + key.size());
    }
  }
  const std::vector<double>& x = nlp->solution();
  if (x.size() == static_cast<std::size_t>(run.variables))
    for (const Block& b : blocks)
      run.factors.emplace_back(nlp->unpack(x.data(), b, 0), nlp->unpack(x.data(), b, 1));
  return run;
}

}  // namespace flatsos::planner::detail
