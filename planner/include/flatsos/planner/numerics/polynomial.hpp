#pragma once
// Univariate real polynomials, coefficients in ascending powers: p(x) = sum_k c[k] x^k.
// Used for joint paths q(t), flat outputs Y(t), torque models and the constraint polynomials
// of the SOS program (those in scaled time s in [0, 1] on each piece).

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <Eigen/Core>

namespace flatsos::planner {

class Polynomial {
 public:
  Polynomial() : c_(Eigen::VectorXd::Zero(1)) {}
  explicit Polynomial(Eigen::VectorXd coefficients);

  const Eigen::VectorXd& coefficients() const { return c_; }
  /// Replaces the coefficients (none: the zero polynomial); reuses the storage when the count
  /// is unchanged, so refitting a path in a control loop allocates nothing.
  void setCoefficients(const Eigen::Ref<const Eigen::VectorXd>& coefficients);
  int degree() const { return static_cast<int>(c_.size()) - 1; }  ///< of the storage (may have zero top)

  double operator()(double x) const;                 ///< Horner
  double derivativeAt(double x, int order) const;    ///< p^(order)(x)
  Polynomial derivative(int order = 1) const;
  double integral(double a, double b) const;
  /// q(s) = p(x0 + h s): the polynomial in a scaled variable.
  Polynomial composeAffine(double x0, double h) const;

  Polynomial operator+(const Polynomial& o) const;
  Polynomial operator-(const Polynomial& o) const;
  Polynomial operator*(const Polynomial& o) const;
  Polynomial operator*(double k) const;

 private:
  Eigen::VectorXd c_;
};

/// Minimum of p on [a, b] and where it is: endpoints and the real critical points (roots of
/// p', from the eigenvalues of the companion matrix; near-real roots are evaluated too, which
/// can only lower the reported value towards the true minimum).
struct IntervalMinimum {
  double value = 0.0;
  double at = 0.0;
};
IntervalMinimum minimum_on_interval(const Polynomial& p, double a, double b);

/// Every root of p (complex, from the companion matrix), top coefficients below 1e-14 of the
/// largest trimmed first; empty for constants.
Eigen::VectorXcd complex_roots(const Polynomial& p);

/// Real roots of p in [a, b] (|imaginary part| <= tol * (1 + |root|)), ascending.
Eigen::VectorXd real_roots_in(const Polynomial& p, double a, double b, double tol = 1e-9);

/// The polynomial of degree n - 1 through (x_k, v_k), k = 0..n-1 (distinct nodes; small n).
Polynomial interpolating_polynomial(const Eigen::VectorXd& nodes, const Eigen::VectorXd& values);

/// n Chebyshev points of the first kind mapped to [0, 1], ascending.
Eigen::VectorXd chebyshev_nodes_unit_interval(int n);

/// Coefficients (ascending powers of t) of the polynomial of degree n_initial + n_terminal - 1
/// that has the given derivatives 0..n_initial-1 at t = 0 and 0..n_terminal-1 at t = T.
/// Solved in scaled time s = t / T for conditioning. Throws std::invalid_argument for T <= 0 or
/// non-finite data.
Polynomial hermite_interpolant(double T, const Eigen::VectorXd& initial_derivatives,
                               const Eigen::VectorXd& terminal_derivatives);

}  // namespace flatsos::planner
