#include "numerics/lukacs_roots.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <optional>
#include <vector>

#include <unsupported/Eigen/Polynomials>

#include "numerics/lukacs_algebra.hpp"

namespace flatsos::planner::detail {

using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {

// Roots closer to the real axis than this (relative) are real: a conjugate pair that close is a
// double real root, and both readings give the same factor (s - m)^2 up to the residual.
constexpr double kRealRootTolerance = 1e-10;

struct RootFactors {
  std::vector<double> at_or_below_zero, at_or_above_one, interior_pair_means;
  std::vector<std::complex<double>> complex_pairs;  // the root with positive imaginary part
};

// None when a computed root is not finite (coefficients of extreme range).
std::optional<RootFactors> sort_roots(const VectorXd& p) {
  Eigen::PolynomialSolver<double, Eigen::Dynamic> solver;
  solver.compute(p);
  if (!solver.roots().allFinite()) return std::nullopt;
  RootFactors f;
  std::vector<double> interior;
  for (const std::complex<double>& z : solver.roots()) {
    if (std::abs(z.imag()) > kRealRootTolerance * (1.0 + std::abs(z))) {
      if (z.imag() > 0.0) f.complex_pairs.push_back(z);
      continue;
    }
    const double r = z.real();
    if (r <= 0.0)
      f.at_or_below_zero.push_back(r);
    else if (r >= 1.0)
      f.at_or_above_one.push_back(r);
    else
      interior.push_back(r);
  }
  std::sort(interior.begin(), interior.end());
  if (interior.size() % 2 == 1) {  // a zero at an end, computed just inside
    const bool low_end = interior.front() < 1.0 - interior.back();
    if (low_end) {
      f.at_or_below_zero.push_back(0.0);
      interior.erase(interior.begin());
    } else {
      f.at_or_above_one.push_back(1.0);
      interior.pop_back();
    }
  }
  for (std::size_t i = 0; i + 1 < interior.size(); i += 2) f.interior_pair_means.push_back(0.5 * (interior[i] + interior[i + 1]));
  return f;
}

void scale_factors(LukacsCertificate& c, double k) {
  c.L0 *= k;
  c.L1 *= k;
}

// c times (a s + b (1 - s)), a, b >= 0.
void multiply_by_linear(LukacsCertificate& c, double a, double b) {
  LukacsCertificate by_s = c, by_one_minus_s = c;
  multiply_certificate(by_s, true);
  scale_factors(by_s, std::sqrt(a));
  multiply_certificate(by_one_minus_s, false);
  scale_factors(by_one_minus_s, std::sqrt(b));
  add_certificate(by_s, by_one_minus_s);
  c = by_s;
}

// c times (s - a)^2 + b^2, written with b^2 = b^2 (s + 1 - s)^2 so that every term has degree 2.
void multiply_by_complex_pair(LukacsCertificate& c, double a, double b) {
  LukacsCertificate out = c, s_squared = c, one_minus_s_squared = c, cross = c;
  multiply_certificate_by_square(out, a);
  multiply_certificate_by_square(s_squared, 0.0);
  scale_factors(s_squared, b);
  multiply_certificate_by_square(one_minus_s_squared, 1.0);
  scale_factors(one_minus_s_squared, b);
  multiply_certificate(cross, true);
  multiply_certificate(cross, false);
  scale_factors(cross, std::sqrt(2.0) * b);
  add_certificate(out, s_squared);
  add_certificate(out, one_minus_s_squared);
  add_certificate(out, cross);
  c = out;
}

}  // namespace

std::optional<LukacsCertificate> certificate_from_roots(const VectorXd& p, GramBasis basis) {
  const Eigen::Index n = p.size() - 1;
  if (n < 1 || p[n] == 0.0 || !p.allFinite()) return std::nullopt;
  const std::optional<RootFactors> roots = sort_roots(p);
  if (!roots) return std::nullopt;
  const RootFactors& f = *roots;
  // p = lead prod (s - z): each root >= 1 is written as -(r - s).
  const double constant = (f.at_or_above_one.size() % 2 == 0 ? 1.0 : -1.0) * p[n];
  if (!(constant > 0.0)) return std::nullopt;
  LukacsCertificate c;
  c.basis = basis;
  c.degree = 0;
  c.L0 = MatrixXd::Constant(1, 1, std::sqrt(constant));
  c.L1 = MatrixXd::Zero(0, 0);
  for (double r : f.at_or_below_zero) multiply_by_linear(c, 1.0 - r, -r);
  for (double r : f.at_or_above_one) multiply_by_linear(c, r - 1.0, r);
  for (double m : f.interior_pair_means) multiply_certificate_by_square(c, m);
  for (const auto& z : f.complex_pairs) multiply_by_complex_pair(c, z.real(), z.imag());
  if (c.degree != n || !c.L0.allFinite() || !c.L1.allFinite()) return std::nullopt;
  return c;
}

}  // namespace flatsos::planner::detail
