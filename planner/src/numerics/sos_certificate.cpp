#include "flatsos/planner/numerics/sos_certificate.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "numerics/ipopt_support.hpp"

// The measurements behind the defaults (basis, factor shape, start, objective) are in the
// comment "Design measurements" at the end of this file.

namespace flatsos::planner {

namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

double binomial(int n, int k) {
  if (k < 0 || k > n) return 0.0;
  double r = 1.0;
  for (int i = 1; i <= k; ++i) r = r * static_cast<double>(n - k + i) / static_cast<double>(i);
  return std::round(r);
}

// ---- The three polynomial families, each indexed by degree n (n + 1 basis functions). ----

// Coefficients (degree n + 1) of s * f, f given by its coefficients c in the degree-n basis.
VectorXd times_s(GramBasis b, const VectorXd& c) {
  const Index n = c.size() - 1;
  VectorXd r = VectorXd::Zero(n + 2);
  for (Index k = 0; k <= n; ++k) {
    switch (b) {
      case GramBasis::Monomial:
        r[k + 1] += c[k];
        break;
      case GramBasis::Bernstein:  // s B^n_k = (k+1)/(n+1) B^{n+1}_{k+1}
        r[k + 1] += c[k] * static_cast<double>(k + 1) / static_cast<double>(n + 1);
        break;
      case GramBasis::Chebyshev:  // s = (1 + x)/2, x T_k = (T_{k+1} + T_{|k-1|})/2
        r[k] += 0.5 * c[k];
        r[k + 1] += 0.25 * c[k];
        r[std::abs(k - 1)] += 0.25 * c[k];
        break;
    }
  }
  return r;
}

// Coefficients (degree n + 1) of (1 - s) * f.
VectorXd times_one_minus_s(GramBasis b, const VectorXd& c) {
  const Index n = c.size() - 1;
  VectorXd r = VectorXd::Zero(n + 2);
  for (Index k = 0; k <= n; ++k) {
    switch (b) {
      case GramBasis::Monomial:
        r[k] += c[k];
        r[k + 1] -= c[k];
        break;
      case GramBasis::Bernstein:  // (1-s) B^n_k = (n+1-k)/(n+1) B^{n+1}_k
        r[k] += c[k] * static_cast<double>(n + 1 - k) / static_cast<double>(n + 1);
        break;
      case GramBasis::Chebyshev:  // 1 - s = (1 - x)/2
        r[k] += 0.5 * c[k];
        r[k + 1] -= 0.25 * c[k];
        r[std::abs(k - 1)] -= 0.25 * c[k];
        break;
    }
  }
  return r;
}

// Coefficients (degree 2d) of phi^d_i * phi^d_j.
VectorXd product(GramBasis b, int d, int i, int j) {
  VectorXd r = VectorXd::Zero(2 * d + 1);
  switch (b) {
    case GramBasis::Monomial:
      r[i + j] = 1.0;
      break;
    case GramBasis::Bernstein:
      r[i + j] = binomial(d, i) * binomial(d, j) / binomial(2 * d, i + j);
      break;
    case GramBasis::Chebyshev:  // T_i T_j = (T_{i+j} + T_{|i-j|})/2
      r[i + j] += 0.5;
      r[std::abs(i - j)] += 0.5;
      break;
  }
  return r;
}

// Column k: the monomial coefficients of phi^n_k.
MatrixXd to_monomial(GramBasis b, int n) {
  const Index m = n + 1;
  MatrixXd t = MatrixXd::Zero(m, m);
  switch (b) {
    case GramBasis::Monomial:
      t.setIdentity();
      break;
    case GramBasis::Bernstein:  // C(n,k) s^k (1-s)^(n-k) = sum_j C(n,k) C(n-k,j-k) (-1)^(j-k) s^j
      for (int k = 0; k <= n; ++k)
        for (int j = k; j <= n; ++j)
          t(j, k) = binomial(n, k) * binomial(n - k, j - k) * (((j - k) % 2 == 0) ? 1.0 : -1.0);
      break;
    case GramBasis::Chebyshev: {  // T_0 = 1, T_1 = 2s - 1, T_{k+1} = 2 (2s - 1) T_k - T_{k-1}
      t(0, 0) = 1.0;
      if (n >= 1) {
        t(0, 1) = -1.0;
        t(1, 1) = 2.0;
      }
      for (Index k = 1; k + 1 <= n; ++k) {
        for (Index j = 0; j <= k; ++j) {
          t(j, k + 1) -= 2.0 * t(j, k);
          t(j + 1, k + 1) += 4.0 * t(j, k);
        }
        t.col(k + 1) -= t.col(k - 1);
      }
      break;
    }
  }
  return t;
}

// Coefficients in the degree-n family of the polynomial with monomial coefficients c (size n+1).
VectorXd from_monomial(GramBasis b, const VectorXd& c) {
  const int n = static_cast<int>(c.size()) - 1;
  switch (b) {
    case GramBasis::Monomial:
      return c;
    case GramBasis::Bernstein: {  // beta_k = sum_{j<=k} C(k,j)/C(n,j) c_j (all weights in [0,1])
      VectorXd beta = VectorXd::Zero(n + 1);
      for (int k = 0; k <= n; ++k)
        for (int j = 0; j <= k; ++j) beta[k] += binomial(k, j) / binomial(n, j) * c[j];
      return beta;
    }
    case GramBasis::Chebyshev:
      break;
  }
  return to_monomial(b, n).triangularView<Eigen::Upper>().solve(c);
}

// ---- The linear map from the Gram matrices to p's coefficients. ----

// coefficient_k(p) = <A0[k], Q0> + <A1[k], Q1> (Frobenius products, A symmetric).
struct LukacsOperator {
  int degree = 0;
  int m0 = 0, m1 = 0;
  std::vector<MatrixXd> A0, A1;
};

LukacsOperator make_operator(GramBasis b, int n) {
  LukacsOperator op;
  op.degree = n;
  const int d = n / 2;
  const bool even = (n % 2 == 0);
  op.m0 = d + 1;
  op.m1 = even ? d : d + 1;
  op.A0.assign(static_cast<std::size_t>(n + 1), MatrixXd::Zero(op.m0, op.m0));
  op.A1.assign(static_cast<std::size_t>(n + 1), MatrixXd::Zero(op.m1, op.m1));
  auto scatter = [](std::vector<MatrixXd>& a, int i, int j, const VectorXd& coef) {
    for (Index k = 0; k < coef.size(); ++k) a[static_cast<std::size_t>(k)](i, j) = coef[k];
  };
  for (int i = 0; i < op.m0; ++i)
    for (int j = 0; j < op.m0; ++j) {
      const VectorXd prod = product(b, d, i, j);
      scatter(op.A0, i, j, even ? prod : times_s(b, prod));
    }
  for (int i = 0; i < op.m1; ++i)
    for (int j = 0; j < op.m1; ++j) {
      if (even) {  // s (1 - s) phi^{d-1}_i phi^{d-1}_j
        scatter(op.A1, i, j, times_s(b, times_one_minus_s(b, product(b, d - 1, i, j))));
      } else {
        scatter(op.A1, i, j, times_one_minus_s(b, product(b, d, i, j)));
      }
    }
  return op;
}

// Family coefficients of v^T Q0 v w0 + v^T Q1 v w1.
VectorXd apply_operator(const LukacsOperator& op, const MatrixXd& Q0, const MatrixXd& Q1) {
  VectorXd r = VectorXd::Zero(op.degree + 1);
  for (std::size_t k = 0; k < op.A0.size(); ++k) {
    if (op.m0 > 0) r[static_cast<Index>(k)] += op.A0[k].cwiseProduct(Q0).sum();
    if (op.m1 > 0) r[static_cast<Index>(k)] += op.A1[k].cwiseProduct(Q1).sum();
  }
  return r;
}

// One deflation step: current = w * next + rest with w = s, 1 - s or (s - r)^2. rest (degree
// < degree of w) is either negligible (empty here: dropped, it shows in the residual) or >= 0 on
// [0, 1] (a constant, or a linear function with both end values >= 0), certified on its own.
struct DeflationStep {
  enum Kind { AtZero, AtOne, Square } kind = Square;
  double r = 0.0;
  VectorXd rest;
};

// How the entries of one m x m factor are laid out among Ipopt's variables, column by column:
// a full square factor (rows 0..m-1 of every column) or a lower-triangular one (rows c..m-1).
struct FactorLayout {
  bool full = true;
  int first_row(int c) const { return full ? 0 : c; }
  int size(int m) const { return full ? m * m : m * (m + 1) / 2; }
  int index(int m, int i, int c) const {
    return full ? c * m + i : c * m - c * (c - 1) / 2 + (i - c);
  }
  void pack(const MatrixXd& L, std::vector<double>& out) const {
    for (int c = 0; c < static_cast<int>(L.cols()); ++c)
      for (int i = first_row(c); i < static_cast<int>(L.rows()); ++i) out.push_back(L(i, c));
  }
};

// ---- The batch NLP. ----

struct Block {
  std::size_t poly = 0;                  // index into the input
  std::vector<DeflationStep> deflation;  // the block certifies q; p = q with these steps undone
  LukacsOperator op;
  VectorXd target;  // normalized family coefficients of q (the deflated p, maybe shifted)
  double normalization = 1.0;  // q_family = normalization * target
  // Constraint weight: Ipopt sees weight * (A(L L^T) - target), so that a violation of tau in
  // every constraint means a relative residual of at most tau in q's monomial coefficients.
  double weight = 1.0;
  int var_offset = 0;           // first variable (L0 entries, then L1 entries)
  int con_offset = 0;           // first constraint (coefficients 0..degree)
  MatrixXd start_L0, start_L1;  // start factors (normalized)
  std::vector<double> start;    // the same as Ipopt variables (set by LukacsNlp)
};

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

// Lower-triangular factor with the same L L^T: L^T = Q R, so L L^T = R^T R; rows of R flipped
// so that the diagonal is >= 0.
// L is r x c (any c): the result is r x r.
MatrixXd lower_triangular_factor(const MatrixXd& L) {
  const Index r = L.rows(), c = L.cols();
  MatrixXd out = MatrixXd::Zero(r, r);
  if (r == 0 || c == 0) return out;
  Eigen::HouseholderQR<MatrixXd> qr(L.transpose());  // c x r
  const Index k = std::min(r, c);
  MatrixXd R = qr.matrixQR().topRows(k).triangularView<Eigen::Upper>();  // k x r
  for (Index i = 0; i < k; ++i)
    if (R(i, i) < 0.0) R.row(i) *= -1.0;
  out.leftCols(k) = R.transpose();
  return out;
}

// Row i: the coefficients in the degree-(d+1) family of w * phi^d_i, w = s or 1 - s; so the
// vector w v_d(s) equals M v_{d+1}(s), and a Gram Q of w^2 v_d^T Q v_d becomes M^T Q M.
MatrixXd multiplication_matrix(GramBasis b, int d, bool by_s) {
  MatrixXd M(d + 1, d + 2);
  for (int i = 0; i <= d; ++i) {
    const VectorXd e = VectorXd::Unit(d + 1, i);
    M.row(i) = (by_s ? times_s(b, e) : times_one_minus_s(b, e)).transpose();
  }
  return M;
}

// The certificate of w q (w = s or 1 - s) from that of q (degree m), in the same basis. One Gram
// is carried over, the other is conjugated by the multiplication matrix:
//   m = 2d:   s q     = s v_d^T Q0 v_d + (1-s) (s v_{d-1})^T Q1 (s v_{d-1}),
//             (1-s) q = s ((1-s) v_{d-1})^T Q1 ((1-s) v_{d-1}) + (1-s) v_d^T Q0 v_d;
//   m = 2d+1: s q     = (s v_d)^T Q0 (s v_d) + s(1-s) v_d^T Q1 v_d,
//             (1-s) q = ((1-s) v_d)^T Q1 ((1-s) v_d) + s(1-s) v_d^T Q0 v_d.
void multiply_certificate(LukacsCertificate& c, bool by_s) {
  const int m = c.degree, d = m / 2;
  MatrixXd L0, L1;
  if (m % 2 == 0) {
    const MatrixXd moved =
        d >= 1 ? MatrixXd(multiplication_matrix(c.basis, d - 1, by_s).transpose() * c.L1)
               : MatrixXd(MatrixXd::Zero(1, 0));  // constant q: no s(1-s) part
    L0 = by_s ? c.L0 : moved;
    L1 = by_s ? moved : c.L0;
  } else {
    L0 = multiplication_matrix(c.basis, d, by_s).transpose() * (by_s ? c.L0 : c.L1);
    L1 = by_s ? c.L1 : c.L0;
  }
  c.L0 = lower_triangular_factor(L0);
  c.L1 = lower_triangular_factor(L1);
  c.degree = m + 1;
}

// Multiplies the certificate by (s - r)^2: both Grams conjugated by the multiplication matrix
// of s - r = (1 - r) s - r (1 - s); the parity of the degree and the weights stay.
void multiply_certificate_by_square(LukacsCertificate& c, double r) {
  const int m = c.degree, d = m / 2;
  const auto M = [&](int k) {
    return MatrixXd((1.0 - r) * multiplication_matrix(c.basis, k, true) -
                    r * multiplication_matrix(c.basis, k, false));
  };
  const MatrixXd L0 = M(d).transpose() * c.L0;
  MatrixXd L1;
  if (m % 2 == 1)
    L1 = M(d).transpose() * c.L1;
  else if (d >= 1)
    L1 = M(d - 1).transpose() * c.L1;
  else
    L1 = MatrixXd::Zero(1, 0);  // constant: the s(1-s) Gram appears, empty
  c.L0 = lower_triangular_factor(L0);
  c.L1 = lower_triangular_factor(L1);
  c.degree = m + 2;
}

// Gram matrices add: [La Lb] [La Lb]^T = La La^T + Lb Lb^T.
void add_certificate(LukacsCertificate& c, const LukacsCertificate& other) {
  MatrixXd L0(c.L0.rows(), c.L0.cols() + other.L0.cols()),
      L1(c.L1.rows(), c.L1.cols() + other.L1.cols());
  L0 << c.L0, other.L0;
  L1 << c.L1, other.L1;
  c.L0 = lower_triangular_factor(L0);
  c.L1 = lower_triangular_factor(L1);
}

// Synthetic division by (s - r): q = (s - r) h + q(r).
std::pair<VectorXd, double> divide_by_linear(const VectorXd& q, double r) {
  const Index m = q.size() - 1;
  VectorXd h(m);
  double acc = q[m];
  for (Index k = m; k >= 1; --k) {
    h[k - 1] = acc;
    acc = q[k - 1] + r * acc;
  }
  return {h, acc};
}

struct Deflation {
  VectorXd q;  // what is left to certify
  std::vector<DeflationStep> steps;
};

// Splits off the factor at the global minimum of q on [0, 1] while that minimum is below
// relative_threshold * max|Bernstein coefficient| (where the L L^T program is nearly singular).
// Valid because the split is at the global minimum: q - rest >= 0 there with a zero at the point
// (double inside). Values below drop_threshold are dropped.
Deflation deflate(const VectorXd& p, double relative_threshold, double drop_threshold) {
  Deflation out;
  VectorXd q = p;
  while (q.size() >= 2) {
    const double size = from_monomial(GramBasis::Bernstein, q).cwiseAbs().maxCoeff();
    const IntervalMinimum m = minimum_on_interval(Polynomial(q), 0.0, 1.0);
    if (!(m.value <= relative_threshold * size)) break;
    DeflationStep step;
    VectorXd next;
    double left = 0.0, right = 0.0;  // rest at s = 0 and s = 1
    if (m.at == 0.0 || m.at == 1.0) {
      const bool at_zero = (m.at == 0.0);
      step.kind = at_zero ? DeflationStep::AtZero : DeflationStep::AtOne;
      // q = s h + q(0) = (1 - s) (-g) + q(1) with q - q(1) = (s - 1) g.
      auto [h, value] = divide_by_linear(q, at_zero ? 0.0 : 1.0);
      next = at_zero ? h : VectorXd(-h);
      left = right = value;
      step.rest = VectorXd::Constant(1, value);
    } else {
      if (q.size() < 3) break;
      step.kind = DeflationStep::Square;
      step.r = m.at;
      const auto [h1, a] = divide_by_linear(q, m.at);   // q = (s - r) h1 + a
      const auto [h2, b] = divide_by_linear(h1, m.at);  // h1 = (s - r) h2 + b
      next = h2;
      step.rest = VectorXd(2);  // a + b (s - r)
      step.rest << a - b * m.at, b;
      left = a - b * m.at;
      right = a + b * (1.0 - m.at);
    }
    if (std::max(std::abs(left), std::abs(right)) <= drop_threshold) {
      step.rest.resize(0);
    } else if (std::min(left, right) < 0.0) {
      break;  // not a clean split (e.g. a slightly negative minimum): leave it to Ipopt
    }
    out.steps.push_back(step);
    q = next;
  }
  out.q = q;
  return out;
}

// The certificate of p from that of the deflated q: the steps undone, last first.
LukacsCertificate undo_deflation(LukacsCertificate c, const std::vector<DeflationStep>& steps);

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

// Diagonal Gram in the Bernstein basis: each diagonal entry feeds exactly one Bernstein
// coefficient, so q = beta_k / A_k(i,i) reproduces p exactly when beta >= 0. Returns the factors
// sqrt(diag) for the s-weighted / square part (g = 0) and the other (g = 1).
std::pair<VectorXd, VectorXd> bernstein_diagonal(const LukacsOperator& bern, const VectorXd& beta) {
  VectorXd q0 = VectorXd::Zero(bern.m0), q1 = VectorXd::Zero(bern.m1);
  for (int k = 0; k <= bern.degree; ++k) {
    const std::size_t ks = static_cast<std::size_t>(k);
    for (int i = 0; i < bern.m0; ++i)
      if (bern.A0[ks](i, i) != 0.0) q0[i] = std::sqrt(std::max(beta[k], 0.0) / bern.A0[ks](i, i));
    for (int i = 0; i < bern.m1; ++i)
      if (bern.A1[ks](i, i) != 0.0) q1[i] = std::sqrt(std::max(beta[k], 0.0) / bern.A1[ks](i, i));
  }
  return {q0, q1};
}

// The closed-form certificate of q (monomial coefficients): diagonal Bernstein Gram of its clipped
// Bernstein coefficients (exact if they are >= 0).
LukacsCertificate bernstein_diagonal_certificate(const VectorXd& q) {
  LukacsCertificate cert;
  cert.degree = static_cast<int>(q.size()) - 1;
  cert.basis = GramBasis::Bernstein;
  const auto [l0, l1] = bernstein_diagonal(make_operator(GramBasis::Bernstein, cert.degree),
                                           from_monomial(GramBasis::Bernstein, q));
  cert.L0 = l0.asDiagonal();
  cert.L1 = l1.asDiagonal();
  cert.from_ipopt = false;
  return cert;
}

// Factor in basis b of the Gram diag(l.^2) given in the Bernstein basis of the same degree:
// v_bern^T = v_b^T R with R = T_b^{-1} T_bern, so G_b = R G R^T.
MatrixXd convert_diagonal_factor(GramBasis b, const VectorXd& l) {
  const Index m = l.size();
  if (m == 0) return MatrixXd(0, 0);
  if (b == GramBasis::Bernstein) return l.asDiagonal();
  const int d = static_cast<int>(m) - 1;
  const MatrixXd R =
      to_monomial(b, d).triangularView<Eigen::Upper>().solve(to_monomial(GramBasis::Bernstein, d));
  const MatrixXd F = R * l.asDiagonal();  // G = F F^T
  Eigen::LLT<MatrixXd> llt(F * F.transpose());
  if (llt.info() == Eigen::Success) return llt.matrixL();
  return F;  // not triangular; never happens with a positive floor
}

LukacsCertificate undo_deflation(LukacsCertificate c, const std::vector<DeflationStep>& steps) {
  for (auto it = steps.rbegin(); it != steps.rend(); ++it) {
    switch (it->kind) {
      case DeflationStep::AtZero:
        multiply_certificate(c, true);
        break;
      case DeflationStep::AtOne:
        multiply_certificate(c, false);
        break;
      case DeflationStep::Square:
        multiply_certificate_by_square(c, it->r);
        break;
    }
    if (it->rest.size() > 0) {
      // rest >= 0 on [0, 1] and of degree <= 1: its Bernstein coefficients (convex combinations
      // of its end values) are >= 0, so the diagonal Bernstein Gram certifies it exactly.
      VectorXd rest = VectorXd::Zero(c.degree + 1);
      rest.head(it->rest.size()) = it->rest;
      LukacsCertificate rc = bernstein_diagonal_certificate(rest);
      if (c.basis != GramBasis::Bernstein) {
        rc.L0 = convert_diagonal_factor(c.basis, rc.L0.diagonal());
        rc.L1 = convert_diagonal_factor(c.basis, rc.L1.diagonal());
        rc.basis = c.basis;
      }
      add_certificate(c, rc);
    }
  }
  return c;
}

void fill_residual(LukacsCertificate& cert, const VectorXd& p_monomial) {
  const Polynomial r = polynomial_from_certificate(cert);
  VectorXd rc = VectorXd::Zero(std::max(r.coefficients().size(), p_monomial.size()));
  rc.head(r.coefficients().size()) += r.coefficients();
  rc.head(p_monomial.size()) -= p_monomial;
  cert.max_coefficient_residual = rc.cwiseAbs().maxCoeff();
  // |e(s)| <= sum_k |e_k| s^k <= sum_k |e_k|, and (Bernstein basis: a partition of unity that is
  // >= 0 on [0, 1]) |e(s)| <= max_k |Bernstein coefficient k of e|.
  cert.residual_bound =
      std::min(rc.cwiseAbs().sum(), from_monomial(GramBasis::Bernstein, rc).cwiseAbs().maxCoeff());
}

struct IpoptRun {
  std::string status;
  int iterations = 0;
  int variables = 0;
  int constraints = 0;
  std::vector<std::pair<MatrixXd, MatrixXd>> factors;  // per block (normalized); empty: no point
  std::string derivative_report;
  int derivative_errors = -1;
};

// One Ipopt call on all the blocks.
IpoptRun run_ipopt(std::vector<Block>& blocks, FactorLayout layout,
                   const CertificationOptions& options, double tol, bool derivative_test) {
  IpoptRun run;
  Ipopt::SmartPtr<LukacsNlp> nlp =
      new LukacsNlp(blocks, layout, options.proximal_weight, options.nonnegative_diagonal);
  run.variables = nlp->num_variables();
  run.constraints = nlp->num_constraints();
  // With the block weights, a constraint violation tau means a relative monomial residual
  // <= tau; ask Ipopt for a tenth of the certification tolerance (re-checked by the caller).
  const double ipopt_tol = std::min(1e-8, 0.1 * tol);
  const detail::IpoptSession app = detail::make_ipopt(ipopt_tol, options.max_iterations);
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

}  // namespace

std::string gram_basis_name(GramBasis basis) {
  switch (basis) {
    case GramBasis::Bernstein:
      return "bernstein";
    case GramBasis::Chebyshev:
      return "chebyshev";
    case GramBasis::Monomial:
      return "monomial";
  }
  return "unknown";
}

Polynomial polynomial_from_certificate(const LukacsCertificate& cert) {
  if (cert.degree < 0) throw std::invalid_argument("Lukacs certificate: negative degree");
  const LukacsOperator op = make_operator(cert.basis, cert.degree);
  if (cert.L0.rows() != op.m0 || cert.L0.cols() != op.m0 || cert.L1.rows() != op.m1 ||
      cert.L1.cols() != op.m1)
    throw std::invalid_argument("Lukacs certificate: factor sizes do not match degree " +
                                std::to_string(cert.degree));
  const VectorXd fam =
      apply_operator(op, cert.L0 * cert.L0.transpose(), cert.L1 * cert.L1.transpose());
  return Polynomial(to_monomial(cert.basis, cert.degree) * fam);
}

CertificationResult certify_nonnegative_on_unit_interval(const std::vector<Polynomial>& polys,
                                                         double tolerance) {
  CertificationOptions options;
  options.tolerance = tolerance;
  return certify_nonnegative_on_unit_interval(polys, options);
}

CertificationResult certify_nonnegative_on_unit_interval(const std::vector<Polynomial>& polys,
                                                         const CertificationOptions& options) {
  using clock = std::chrono::steady_clock;
  const auto t_start = clock::now();
  const double tol = options.tolerance;
  if (!(tol > 0.0) || !std::isfinite(tol))
    throw std::invalid_argument("SOS certificate: tolerance must be > 0");
  for (const Polynomial& p : polys)
    if (!p.coefficients().allFinite())
      throw std::invalid_argument("SOS certificate: polynomial with non-finite coefficients");

  const std::size_t np = polys.size();
  CertificationResult res;
  res.certificates.resize(np);
  res.certified.assign(np, false);
  res.interval_minimum.assign(np, 0.0);
  res.refused_by_precheck.assign(np, false);

  std::vector<Block> blocks;
  FactorLayout layout;
  layout.full = !options.triangular_factors;
  for (std::size_t ip = 0; ip < np; ++ip) {
    const VectorXd& c = polys[ip].coefficients();
    LukacsCertificate& cert = res.certificates[ip];
    const double scale = c.cwiseAbs().maxCoeff();
    cert.scale = scale;
    Index len = c.size();
    while (len > 1 && std::abs(c[len - 1]) <= std::numeric_limits<double>::epsilon() * scale) --len;
    const int n = static_cast<int>(len) - 1;
    cert.degree = n;
    const VectorXd pc = c.head(len);
    res.interval_minimum[ip] = minimum_on_interval(Polynomial(pc), 0.0, 1.0).value;
    if (options.precheck && res.interval_minimum[ip] < -tol * scale) {
      res.refused_by_precheck[ip] = true;
      cert.L0.resize(0, 0);
      cert.L1.resize(0, 0);
      continue;
    }

    // Closed form: diagonal Bernstein Gram (exact when the Bernstein coefficients are >= 0;
    // always used for degree <= 1, where the Bernstein coefficients are p(0), p(1)).
    const auto closed_form = [&](const VectorXd& q) {
      return scale == 0.0 || q.size() <= 2 ||
             (options.closed_form_shortcut &&
              from_monomial(GramBasis::Bernstein, q).minCoeff() >= 0.0);
    };
    const auto finish = [&](const LukacsCertificate& qc, const std::vector<DeflationStep>& steps) {
      LukacsCertificate full = undo_deflation(qc, steps);
      full.scale = scale;
      full.deflation_steps = static_cast<int>(steps.size());
      fill_residual(full, c);
      return full;
    };
    if (closed_form(pc)) {
      cert = finish(bernstein_diagonal_certificate(pc), {});
      continue;
    }
    // Near-zero minima are split off exactly (at the global minimum: s, 1 - s or (s - r)^2,
    // the small remainder certified apart): the L L^T program is nearly singular there.
    Deflation defl;
    defl.q = pc;
    if (options.deflate_near_zeros)
      defl = deflate(pc, options.deflation_threshold, 0.01 * tol * scale);
    const VectorXd& q = defl.q;
    const int nq = static_cast<int>(q.size()) - 1;
    if (closed_form(q)) {
      cert = finish(bernstein_diagonal_certificate(q), defl.steps);
      continue;
    }

    // Ipopt block for q. A computed minimum slightly below zero (within the tolerance, else
    // refused above) would make the exact problem infeasible and Ipopt would iterate to its
    // limit: the block certifies q + delta instead, and delta counts in the residual against p.
    const double q_scale = q.cwiseAbs().maxCoeff();
    VectorXd target_poly = q;
    if (options.precheck) {
      const double q_min = defl.steps.empty() ? res.interval_minimum[ip]
                                              : minimum_on_interval(Polynomial(q), 0.0, 1.0).value;
      if (q_min < 0.0) target_poly[0] += -q_min + 0.01 * tol * q_scale;
    }
    Block b;
    b.poly = ip;
    b.deflation = defl.steps;
    b.op = make_operator(options.basis, nq);
    const VectorXd fam = from_monomial(options.basis, target_poly);
    b.normalization = fam.cwiseAbs().maxCoeff();
    b.target = fam / b.normalization;
    b.weight = to_monomial(options.basis, nq).cwiseAbs().rowwise().sum().maxCoeff() *
               b.normalization / q_scale;
    // Start: the diagonal Bernstein Gram of the normalized Bernstein coefficients, clipped from
    // below at start_floor times the largest.
    const VectorXd beta_t = from_monomial(GramBasis::Bernstein, target_poly);
    const double bmax = beta_t.cwiseAbs().maxCoeff();
    const VectorXd beta_start =
        (beta_t / b.normalization).cwiseMax(options.start_floor * bmax / b.normalization);
    const auto [l0, l1] = bernstein_diagonal(make_operator(GramBasis::Bernstein, nq), beta_start);
    b.start_L0 = convert_diagonal_factor(options.basis, l0);
    b.start_L1 = convert_diagonal_factor(options.basis, l1);
    blocks.push_back(std::move(b));
  }

  if (!blocks.empty()) {
    const auto t_ipopt = clock::now();
    const auto certify_blocks = [&](const std::vector<Block>& bs, const IpoptRun& run) {
      for (std::size_t bi = 0; bi < bs.size(); ++bi) {
        const Block& b = bs[bi];
        if (run.factors.size() != bs.size()) continue;  // Ipopt returned no point
        LukacsCertificate cand;
        cand.degree = b.op.degree;
        cand.basis = options.basis;
        const double root = std::sqrt(b.normalization);
        cand.L0 = lower_triangular_factor(run.factors[bi].first * root);
        cand.L1 = lower_triangular_factor(run.factors[bi].second * root);
        cand = undo_deflation(cand, b.deflation);
        cand.scale = res.certificates[b.poly].scale;
        cand.deflation_steps = static_cast<int>(b.deflation.size());
        cand.from_ipopt = true;
        fill_residual(cand, polys[b.poly].coefficients());
        LukacsCertificate& cert = res.certificates[b.poly];
        if (!cert.from_ipopt || !(cert.max_coefficient_residual <= cand.max_coefficient_residual))
          cert = cand;
      }
    };
    for (const Block& b : blocks) {  // until Ipopt gives something better
      LukacsCertificate& cert = res.certificates[b.poly];
      cert.L0.resize(0, 0);
      cert.L1.resize(0, 0);
      cert.from_ipopt = false;
    }
    const IpoptRun first = run_ipopt(blocks, layout, options, tol, options.derivative_test);
    certify_blocks(blocks, first);
    res.ipopt_calls = 1;
    res.ipopt_status = first.status;
    res.ipopt_iterations = first.iterations;
    res.ipopt_variables = first.variables;
    res.ipopt_constraints = first.constraints;
    res.derivative_test_report = first.derivative_report;
    res.derivative_test_errors = first.derivative_errors;
    // Blocks the first layout left uncertified get one more chance, all in one more call, with
    // the other factor layout (they fail on different polynomials, see the measurements below).
    if (options.retry_other_layout) {
      std::vector<Block> again;
      for (const Block& b : blocks)
        if (!(res.certificates[b.poly].max_coefficient_residual <=
              tol * res.certificates[b.poly].scale))
          again.push_back(b);
      if (!again.empty()) {
        FactorLayout other = layout;
        other.full = !layout.full;
        const IpoptRun second = run_ipopt(again, other, options, tol, false);
        certify_blocks(again, second);
        res.ipopt_calls = 2;
        res.retried_blocks = static_cast<int>(again.size());
        res.retry_status = second.status;
        res.ipopt_iterations += second.iterations;
      }
    }
    res.solve_seconds = std::chrono::duration<double>(clock::now() - t_ipopt).count();
  }

  res.all_certified = true;
  for (std::size_t ip = 0; ip < np; ++ip) {
    const LukacsCertificate& cert = res.certificates[ip];
    res.certified[ip] = !res.refused_by_precheck[ip] && cert.L0.size() + cert.L1.size() > 0 &&
                        cert.max_coefficient_residual <= tol * cert.scale;
    if (cert.scale == 0.0) res.certified[ip] = true;  // p == 0
    res.all_certified = res.all_certified && res.certified[ip];
  }
  res.total_seconds = std::chrono::duration<double>(clock::now() - t_start).count();
  return res;
}

}  // namespace flatsos::planner

// Design measurements (Release, Debian 12, Ipopt 3.11.9 + MUMPS; batches of 40 random polynomials
// c_k ~ N(0,1) shifted so that min over [0,1] = margin * max|c_k|; 5 seeds; closed-form shortcut
// off; iterations per call of the L L^T program alone, i.e. without the splits):
//
//                                  margin 1e-3         margin 0 (double root or end zero)
//                                  deg 4    deg 6      deg 4              deg 6
//   full factors, Bernstein        7.8      7.8        19.0               21.0
//   lower-triangular factors      12.6     12.2        75 (183/200 ok)   100 (105/200 ok)
//   Chebyshev basis T_k(2s-1)      7.8      8.4        19.8               23.4
//   monomial basis                 8.0      8.6        17.6               18.6
//   start floor 0.001 / 0.1 / 0.5  7.8/8.0/10.0        19.4/19.8/20.8 (deg 4)
//   proximal term w = 1e-3         9.8      9.8        32.4               83 (188/200 ok)
//   bounds L_ii >= 0              14.4     16.4        97 (182/200 ok)   100 (175/200 ok)
//
// So: full square factors (the triangular ones, DESIGN.md's recipe, stall at singular solutions;
// the certificate is made triangular afterwards by a QR), zero objective, no bounds, start floor
// 0.01. Bernstein is chosen over the monomial basis for the exact diagonal start and closed form,
// and because the residual bound on [0, 1] is tight in it; Chebyshev has no advantage here.
// Before the per-block constraint weights, Chebyshev and Bernstein residuals (measured in
// monomial coefficients) missed a 1e-9 tolerance at degree 8 on margin-0 polynomials.
//
// What the L L^T program alone cannot do (single polynomials, full factors, 100-200 iterations
// without convergence): zeros of multiplicity >= 2 at s = 0 (s^2 g, s^3), (1-s)^3 (s + 0.1),
// and double roots close to an end (e.g. at s = 0.008); triangular factors fail on others. The
// splits at near-zero minima (deflate_near_zeros) remove these: on margin-0 batches the program
// then takes 2.8 (deg 4) and 3.6 (deg 6) iterations per call, and a table of s^a (1-s)^b g with
// a, b <= 3 is certified throughout. The retry with the other layout remains as a safety net.
//
// Fixed cost: an Ipopt call with 40 quartics (13 variables and 5 constraints each) at 8
// iterations takes about 11 ms; 40 sextics (25 variables, 7 constraints) about 15 ms.
