#pragma once
// The natural quintic interpolating spline: the C^4 piecewise quintic through (x_i, y_i) whose
// third and fourth derivatives vanish at both end knots. It is the function that minimises the
// integral of (f''')^2 among all interpolants (Schoenberg, Proc. Natl. Acad. Sci. 52:947-950,
// 1964), and the limit of Woltring's GCVSPL smoothing spline of half-order 3 at zero smoothing
// (Woltring, Adv. Eng. Software 8:104-113, 1986), which is what OpenSim's GCVSplineSet(5, ...)
// builds from coordinate data. Because the end conditions ask f''' = 0, it reproduces
// polynomials of degree <= 2 exactly but not cubics or above.
//
// Built from the unknown first and second derivatives at the knots: on each interval the
// quintic is the Hermite interpolant of (value, slope, curvature) at its two ends, and
// continuity of the third and fourth derivatives at interior knots, with the four end
// conditions, gives a banded linear system for them.

#include <vector>

namespace flatsos::plugin {

class NaturalQuinticSpline {
 public:
  /// Throws std::invalid_argument unless x is strictly increasing, x and y are finite, of equal
  /// size, with at least 6 knots (GCVSPL's minimum for a quintic).
  NaturalQuinticSpline(std::vector<double> x, const std::vector<double>& y);

  /// The spline's derivative of the given order (0 = value, up to 5) at x, for x in
  /// [x_front, x_back]; throws std::invalid_argument outside or for another order.
  double derivative(double x, int order) const;
  /// The same anywhere: beyond the knots, the first or last interval's quintic continued (a
  /// tracked motion's horizon may reach past its last sample). Throws for a non-finite x.
  double continuedDerivative(double x, int order) const;
  double value(double x) const { return derivative(x, 0); }
  double firstDerivative(double x) const { return derivative(x, 1); }
  double secondDerivative(double x) const { return derivative(x, 2); }

  const std::vector<double>& knots() const { return x_; }

 private:
  std::vector<double> x_;
  /// Per interval, the quintic in s = (x - x_i)/h_i: coefficients of s^0 .. s^5.
  std::vector<std::vector<double>> coefficients_;
};

}  // namespace flatsos::plugin
