#pragma once
// A musculotendon length as a polynomial of joint coordinates, in the convention of OpenSim's
// MultivariatePolynomialFunction (what its FunctionBasedPath and PolynomialPathFitter write):
// `dimension` arguments x_0 .. x_{d-1}, `order` the largest sum of exponents in one term, and
// the coefficients in ascending powers starting from the last argument. The terms run as nested
// loops over the exponents, the first argument's outermost: for (X, Y, Z) and order 3,
//   1, Z, Z^2, Z^3, Y, YZ, YZ^2, Y^2, Y^2 Z, Y^3, X, XZ, XZ^2, XY, XYZ, XY^2, X^2, X^2 Z, X^2 Y, X^3.
// Values and exact time derivatives along a curve x(t) (truncated Taylor arithmetic); partial
// derivatives as polynomials of the same kind. Pure math: no Eigen, no Simbody.

#include <vector>

namespace flatsos::muscles {

class LengthPolynomial {
 public:
  /// Largest number of arguments (a muscle path depends on a handful of coordinates).
  static constexpr int kMaxDimension = 16;
  /// Most time derivatives timeDerivatives() gives: the value and four derivatives.
  static constexpr int kMaxJetCount = 5;

  /// The zero polynomial of no arguments.
  LengthPolynomial() = default;
  /// Throws std::invalid_argument for a dimension outside [0, kMaxDimension], a negative order,
  /// a coefficient count other than termCount(dimension, order) (the message gives both), or a
  /// coefficient that is not finite (the message gives its index).
  LengthPolynomial(int dimension, int order, std::vector<double> coefficients);

  /// binom(dimension + order, order): the number of terms; saturates at 1e9.
  static long termCount(int dimension, int order);
  /// The exponents of every term in the coefficients' order (termCount rows of `dimension`).
  static std::vector<std::vector<int>> termExponents(int dimension, int order);

  int dimension() const { return dimension_; }
  int order() const { return order_; }
  /// As given, in OpenSim's order.
  const std::vector<double>& coefficients() const { return coefficients_; }
  /// True when no term of positive degree in argument k has a nonzero coefficient.
  bool independentOf(int k) const;

  /// P(x); x has dimension() entries.
  double value(const double* x) const;
  /// dP/dx_k as a polynomial of the same arguments, of order max(order - 1, 0).
  LengthPolynomial derivative(int k) const;
  /// P with argument k fixed at `value`: a polynomial of the other arguments (same order, one
  /// dimension fewer). Throws std::invalid_argument for k outside [0, dimension) or a value that
  /// is not finite.
  LengthPolynomial withArgumentHeld(int k, double value) const;
  /// d^j/dt^j P(x(t)) for j = 0 .. count - 1 (count <= kMaxJetCount) into out[j], from the
  /// time derivatives of the arguments: x_jet[j * dimension() + k] = d^j x_k / dt^j.
  void timeDerivatives(const double* x_jet, int count, double* out) const;

 private:
  int dimension_ = 0, order_ = 0;
  std::vector<double> coefficients_{0.0};
  // The nonzero terms, for evaluation: coefficient and exponents (dimension_ per term).
  std::vector<double> term_coefficient_;
  std::vector<int> term_exponents_;
  // timeDerivatives' table of the arguments' powers x_k^e (e up to the largest exponent of x_k
  // in a term) as series: argument k's powers start at row power_row_[k]; dimension_ + 1
  // entries, the last one the table's size.
  std::vector<int> power_row_;
  static constexpr int kMaxPowerRows = 64;  // a table on the stack: 3 arguments to order 20
};

}  // namespace flatsos::muscles
