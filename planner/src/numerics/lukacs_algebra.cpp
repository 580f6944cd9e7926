#include "numerics/lukacs_algebra.hpp"

#include <algorithm>
#include <cmath>

namespace flatsos::planner::detail {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

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

}  // namespace flatsos::planner::detail
