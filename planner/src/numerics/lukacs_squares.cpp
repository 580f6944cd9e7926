#include "numerics/lukacs_squares.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>
#include <vector>

namespace flatsos::planner::detail {

namespace {

using Eigen::VectorXd;

constexpr double kEnd = 1e-10;  // a real root this close to 0 or 1 is at the end

VectorXd product(const VectorXd& a, const VectorXd& b) {
  if (a.size() == 0 || b.size() == 0) return VectorXd();
  VectorXd r = VectorXd::Zero(a.size() + b.size() - 1);
  for (Eigen::Index i = 0; i < a.size(); ++i) r.segment(i, b.size()) += a[i] * b;
  return r;
}

// a + sign * b, padded to the longer one, then cut or padded to `size` (what is cut is zero by
// the degree count).
VectorXd sum(const VectorXd& a, const VectorXd& b, double sign, Eigen::Index size) {
  VectorXd r = VectorXd::Zero(std::max({a.size(), b.size(), size}));
  r.head(a.size()) += a;
  r.head(b.size()) += sign * b;
  r.conservativeResize(size);
  return r;
}

const VectorXd& s_times_one_minus_s() {
  static const VectorXd d = (VectorXd(3) << 0.0, 1.0, -1.0).finished();
  return d;
}

// A factor q = c0 + c1 s + c2 s^2 >= 0 on [0, 1] as F^2 + s(1-s) G^2, F linear, G constant:
// F(0) = sqrt(q(0)), F(1) = -sqrt(q(1)) (q - F^2 then vanishes at 0 and 1, so it is
// kappa s(1-s); opposite signs give the largest kappa = c1 + 2 q(0) + 2 sqrt(q(0) q(1))).
void factor_squares(const Eigen::Vector3d& q, VectorXd& F, VectorXd& G) {
  const double q0 = std::max(0.0, q[0]), q1 = std::max(0.0, q.sum());
  const double beta = std::sqrt(q0), alpha = -std::sqrt(q1) - beta;
  const double kappa = q[1] - 2.0 * alpha * beta;
  F = (VectorXd(2) << beta, alpha).finished();
  G = VectorXd::Constant(1, std::sqrt(std::max(0.0, kappa)));
}

// The quadratic (or linear) factor through the given roots, signed to be positive at s = 1/2 and
// scaled to a largest coefficient of 1 (far roots would otherwise overflow the product).
Eigen::Vector3d normalized(Eigen::Vector3d q) {
  if (q[0] + 0.5 * q[1] + 0.25 * q[2] < 0.0) q = -q;
  return q / q.cwiseAbs().maxCoeff();
}

}  // namespace

LukacsSquares lukacs_squares(const Polynomial& p, int half_degree) {
  if (half_degree < 0) throw std::invalid_argument("lukacs_squares: negative half degree");
  const VectorXd& c = p.coefficients();
  const double scale = c.cwiseAbs().maxCoeff();
  Eigen::Index n = c.size() - 1;
  while (n > 0 && std::abs(c[n]) <= 1e-14 * scale) --n;
  if (n > 2 * half_degree)
    throw std::invalid_argument("lukacs_squares: degree " + std::to_string(n) + " above 2 x " +
                                std::to_string(half_degree));
  LukacsSquares out{VectorXd::Zero(half_degree + 1), VectorXd::Zero(half_degree)};
  if (!(scale > 0.0)) return out;

  // Factors >= 0 on [0, 1] of degree <= 2 whose product is p up to a constant.
  std::vector<Eigen::Vector3d> factors;
  std::vector<double> inside, outside;
  for (const std::complex<double>& z : complex_roots(p)) {
    if (std::abs(z.imag()) <= 1e-9 * (1.0 + std::abs(z))) {
      // Simple zeros at the ends are allowed (s and 1 - s are >= 0): they count as outside.
      (z.real() > kEnd && z.real() < 1.0 - kEnd ? inside : outside).push_back(z.real());
    } else if (z.imag() > 0.0) {
      factors.push_back(normalized({std::norm(z), -2.0 * z.real(), 1.0}));  // |s - z|^2
    }
  }
  // Zeros in [0, 1] of a p >= 0 are double, split by rounding: each pair becomes (s - mid)^2.
  std::sort(inside.begin(), inside.end());
  for (std::size_t i = 0; i + 1 < inside.size(); i += 2) {
    const double m = 0.5 * (inside[i] + inside[i + 1]);
    factors.push_back(normalized({m * m, -2.0 * m, 1.0}));
  }
  if (inside.size() % 2 == 1) outside.push_back(inside.back());  // p changes sign: a start only
  std::sort(outside.begin(), outside.end());
  for (std::size_t i = 0; i < outside.size(); i += 2) {
    const double r = outside[i];
    if (i + 1 < outside.size()) {
      const double r2 = outside[i + 1];
      factors.push_back(normalized({r * r2, -(r + r2), 1.0}));
    } else {
      factors.push_back(normalized({-r, 1.0, 0.0}));
    }
  }

  VectorXd f = VectorXd::Ones(1), g;
  const VectorXd& d = s_times_one_minus_s();
  for (const Eigen::Vector3d& q : factors) {
    VectorXd F, G;
    factor_squares(q, F, G);
    const Eigen::Index k = f.size();  // factors so far + 1
    const VectorXd f_next = sum(product(f, F), product(product(d, g), G), -1.0, k + 1);
    g = sum(product(f, G), product(g, F), 1.0, k);
    f = f_next;
  }
  // The constant: least squares between p and the product's coefficients.
  const LukacsSquares unit{f, g};
  const VectorXd composed = lukacs_squares_polynomial(unit);
  const VectorXd target = sum(c, VectorXd(), 1.0, composed.size());
  const double kappa = std::abs(target.dot(composed) / composed.squaredNorm());
  out.f.head(f.size()) = std::sqrt(kappa) * f;
  out.g.head(g.size()) = std::sqrt(kappa) * g;
  return out;
}

VectorXd lukacs_squares_polynomial(const LukacsSquares& sq) {
  const Eigen::Index size = 2 * sq.f.size() - 1;
  return sum(product(sq.f, sq.f), product(s_times_one_minus_s(), product(sq.g, sq.g)), 1.0, size);
}

}  // namespace flatsos::planner::detail
