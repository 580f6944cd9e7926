#include "numerics/lukacs_basis.hpp"

#include <cmath>

namespace flatsos::planner::detail {

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

}  // namespace flatsos::planner::detail
