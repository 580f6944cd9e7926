#include "flatsos/planner/numerics/polynomial.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>
#include <unsupported/Eigen/Polynomials>

namespace flatsos::planner {

Polynomial::Polynomial(Eigen::VectorXd coefficients) : c_(std::move(coefficients)) {
  if (c_.size() == 0) c_ = Eigen::VectorXd::Zero(1);
}

void Polynomial::setCoefficients(const Eigen::Ref<const Eigen::VectorXd>& c) {
  if (c.size() == 0) {
    c_.setZero(1);
  } else {
    c_ = c;
  }
}

double Polynomial::operator()(double x) const {
  double v = 0.0;
  for (Eigen::Index k = c_.size() - 1; k >= 0; --k) v = v * x + c_[k];
  return v;
}

Polynomial Polynomial::derivative(int order) const {
  Eigen::VectorXd d = c_;
  for (int o = 0; o < order; ++o) {
    if (d.size() <= 1) return Polynomial();
    Eigen::VectorXd next(d.size() - 1);
    for (Eigen::Index k = 1; k < d.size(); ++k) next[k - 1] = static_cast<double>(k) * d[k];
    d = next;
  }
  return Polynomial(d);
}

double Polynomial::derivativeAt(double x, int order) const {
  if (order == 0) return (*this)(x);
  // Horner on the derivative's coefficients k!/(k-order)! c_k without allocating.
  double v = 0.0;
  for (Eigen::Index k = c_.size() - 1; k >= order; --k) {
    double falling = 1.0;
    for (int j = 0; j < order; ++j) falling *= static_cast<double>(k - j);
    v = v * x + falling * c_[k];
  }
  return v;
}

double Polynomial::integral(double a, double b) const {
  double va = 0.0, vb = 0.0;
  for (Eigen::Index k = c_.size() - 1; k >= 0; --k) {
    const double ck = c_[k] / static_cast<double>(k + 1);
    va = va * a + ck;
    vb = vb * b + ck;
  }
  return vb * b - va * a;
}

Polynomial Polynomial::composeAffine(double x0, double h) const {
  // Horner in polynomial arithmetic: q = (...(c_n (x0 + h s) + c_{n-1})(x0 + h s) + ...).
  const Eigen::Index n = c_.size();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(n);
  q[0] = c_[n - 1];
  for (Eigen::Index k = n - 2; k >= 0; --k) {
    // q <- q * (x0 + h s) + c_k
    for (Eigen::Index j = n - 1; j >= 1; --j) q[j] = q[j] * x0 + q[j - 1] * h;
    q[0] = q[0] * x0 + c_[k];
  }
  return Polynomial(q);
}

Polynomial Polynomial::operator+(const Polynomial& o) const {
  Eigen::VectorXd r = Eigen::VectorXd::Zero(std::max(c_.size(), o.c_.size()));
  r.head(c_.size()) += c_;
  r.head(o.c_.size()) += o.c_;
  return Polynomial(r);
}
Polynomial Polynomial::operator-(const Polynomial& o) const { return *this + o * -1.0; }
Polynomial Polynomial::operator*(double k) const { return Polynomial(c_ * k); }
Polynomial Polynomial::operator*(const Polynomial& o) const {
  Eigen::VectorXd r = Eigen::VectorXd::Zero(c_.size() + o.c_.size() - 1);
  for (Eigen::Index i = 0; i < c_.size(); ++i)
    for (Eigen::Index j = 0; j < o.c_.size(); ++j) r[i + j] += c_[i] * o.c_[j];
  return Polynomial(r);
}

Eigen::VectorXcd complex_roots(const Polynomial& p) {
  const Eigen::VectorXd& c = p.coefficients();
  const double scale = c.cwiseAbs().maxCoeff();
  Eigen::Index n = c.size();
  while (n > 1 && std::abs(c[n - 1]) <= 1e-14 * scale) --n;
  if (n <= 1 || scale == 0.0) return Eigen::VectorXcd();
  if (n == 2) {
    Eigen::VectorXcd r(1);
    r[0] = -c[0] / c[1];
    return r;
  }
  Eigen::PolynomialSolver<double, Eigen::Dynamic> solver;
  solver.compute(c.head(n));
  return solver.roots();
}

Eigen::VectorXd real_roots_in(const Polynomial& p, double a, double b, double tol) {
  std::vector<double> out;
  for (const auto& r : complex_roots(p))
    if (std::abs(r.imag()) <= tol * (1.0 + std::abs(r)) && r.real() >= a && r.real() <= b)
      out.push_back(r.real());
  std::sort(out.begin(), out.end());
  return Eigen::Map<Eigen::VectorXd>(out.data(), static_cast<Eigen::Index>(out.size()));
}

IntervalMinimum minimum_on_interval(const Polynomial& p, double a, double b) {
  IntervalMinimum best{p(a), a};
  auto consider = [&](double x) {
    if (x < a || x > b) return;
    const double v = p(x);
    if (v < best.value) best = {v, x};
  };
  consider(b);
  // Every root's real part is a candidate: exact critical points and near-real pairs alike.
  for (const auto& r : complex_roots(p.derivative())) consider(r.real());
  return best;
}

Polynomial interpolating_polynomial(const Eigen::VectorXd& x, const Eigen::VectorXd& v) {
  if (x.size() != v.size() || x.size() == 0) throw std::invalid_argument("interpolation: need as many values as nodes");
  const Eigen::Index n = x.size();
  Eigen::MatrixXd V(n, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) V(i, j) = std::pow(x[i], static_cast<double>(j));
  return Polynomial(V.fullPivLu().solve(v));
}

Eigen::VectorXd chebyshev_nodes_unit_interval(int n) {
  Eigen::VectorXd x(n);
  for (int c = 0; c < n; ++c) x[c] = 0.5 * (1.0 - std::cos(3.14159265358979323846 * (2.0 * c + 1.0) / (2.0 * n)));
  return x;
}

Polynomial hermite_interpolant(double T, const Eigen::VectorXd& d0, const Eigen::VectorXd& dT) {
  if (!(T > 0.0) || !std::isfinite(T)) throw std::invalid_argument("joint path: horizon T must be > 0 s");
  if (!d0.allFinite() || !dT.allFinite())
    throw std::invalid_argument("joint path: boundary derivatives must be finite");
  const Eigen::Index n = d0.size() + dT.size();
  if (n == 0) throw std::invalid_argument("joint path: no boundary conditions");
  // In s = t / T: d^k/ds^k = T^k d^k/dt^k. Row for derivative k at s0: sum_j j!/(j-k)! s0^(j-k) c_j.
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd rhs(n);
  Eigen::Index row = 0;
  auto add_rows = [&](const Eigen::VectorXd& d, double s0) {
    double tk = 1.0;
    for (Eigen::Index k = 0; k < d.size(); ++k, ++row) {
      for (Eigen::Index j = k; j < n; ++j) {
        double falling = 1.0;
        for (Eigen::Index i = 0; i < k; ++i) falling *= static_cast<double>(j - i);
        m(row, j) = falling * std::pow(s0, static_cast<double>(j - k));
      }
      rhs[row] = d[k] * tk;
      tk *= T;
    }
  };
  add_rows(d0, 0.0);
  add_rows(dT, 1.0);
  const Eigen::VectorXd cs = m.fullPivLu().solve(rhs);
  Eigen::VectorXd ct(n);
  double tpow = 1.0;
  for (Eigen::Index j = 0; j < n; ++j, tpow *= T) ct[j] = cs[j] / tpow;
  return Polynomial(ct);
}

}  // namespace flatsos::planner
