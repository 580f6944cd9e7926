#include "flatsos/plugin/io/opensim_function.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace flatsos::plugin {

OpenSimFunction OpenSimFunction::identity() { return linear(1.0, 0.0); }

OpenSimFunction OpenSimFunction::constant(double value) {
  OpenSimFunction f;
  f.coefficients_ = {value};
  return f;
}

OpenSimFunction OpenSimFunction::linear(double slope, double intercept) {
  OpenSimFunction f;
  f.kind_ = Kind::Linear;
  f.type_name_ = "LinearFunction";
  f.coefficients_ = {slope, intercept};
  return f;
}

OpenSimFunction OpenSimFunction::polynomial(std::vector<double> coefficients_highest_first) {
  if (coefficients_highest_first.empty()) throw std::invalid_argument("PolynomialFunction: no coefficients");
  OpenSimFunction f;
  f.kind_ = Kind::Polynomial;
  f.type_name_ = "PolynomialFunction";
  f.coefficients_ = std::move(coefficients_highest_first);
  return f;
}

// The cubic through each interval with the end conditions of Forsythe, Malcolm and Moler
// ("Computer Methods for Mathematical Computations", 1977): the third derivatives at the ends
// are those of the cubics through the first and the last four knots (a parabola with three
// knots, a line with two), which is what OpenSim's SimmSpline computes.
OpenSimFunction OpenSimFunction::simmSpline(std::vector<double> x, std::vector<double> y) {
  const std::size_t n = x.size();
  if (n < 2 || y.size() != n)
    throw std::invalid_argument("SimmSpline: needs at least 2 knots and as many y as x (got " + std::to_string(n) +
                                " x and " + std::to_string(y.size()) + " y)");
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(x[i]) || !std::isfinite(y[i]) || (i > 0 && !(x[i] > x[i - 1])))
      throw std::invalid_argument("SimmSpline: knots must be finite and x strictly increasing (knot " +
                                  std::to_string(i) + ")");
  OpenSimFunction f;
  f.kind_ = Kind::SimmSpline;
  f.type_name_ = "SimmSpline";
  std::vector<double> b(n, 0.0), c(n, 0.0), d(n, 0.0);
  if (n == 2) {
    b[0] = b[1] = (y[1] - y[0]) / (x[1] - x[0]);
  } else {
    const std::size_t last = n - 1;
    // Tridiagonal system for c (half the second derivatives): d holds the interval widths, b
    // the diagonal, c the right-hand side until it is solved.
    d[0] = x[1] - x[0];
    c[1] = (y[1] - y[0]) / d[0];
    for (std::size_t i = 1; i < last; ++i) {
      d[i] = x[i + 1] - x[i];
      b[i] = 2.0 * (d[i - 1] + d[i]);
      c[i + 1] = (y[i + 1] - y[i]) / d[i];
      c[i] = c[i + 1] - c[i];
    }
    b[0] = -d[0];
    b[last] = -d[last - 1];
    c[0] = 0.0;
    c[last] = 0.0;
    if (n > 3) {
      c[0] = c[2] / (x[3] - x[1]) - c[1] / (x[2] - x[0]);
      c[last] = c[last - 1] / (x[last] - x[last - 2]) - c[last - 2] / (x[last - 1] - x[last - 3]);
      c[0] = c[0] * d[0] * d[0] / (x[3] - x[0]);
      c[last] = -c[last] * d[last - 1] * d[last - 1] / (x[last] - x[last - 3]);
    }
    for (std::size_t i = 1; i <= last; ++i) {  // forward elimination
      const double t = d[i - 1] / b[i - 1];
      b[i] -= t * d[i - 1];
      c[i] -= t * c[i - 1];
    }
    c[last] /= b[last];  // back substitution
    for (std::size_t k = last; k-- > 0;) c[k] = (c[k] - d[k] * c[k + 1]) / b[k];
    b[last] = (y[last] - y[last - 1]) / d[last - 1] + d[last - 1] * (c[last - 1] + 2.0 * c[last]);
    for (std::size_t i = 0; i < last; ++i) {
      b[i] = (y[i + 1] - y[i]) / d[i] - d[i] * (c[i + 1] + 2.0 * c[i]);
      d[i] = (c[i + 1] - c[i]) / d[i];
      c[i] *= 3.0;
    }
    c[last] *= 3.0;
    d[last] = d[last - 1];
  }
  f.x_ = std::move(x);
  f.y_ = std::move(y);
  f.b_ = std::move(b);
  f.c_ = std::move(c);
  f.d_ = std::move(d);
  return f;
}

OpenSimFunction OpenSimFunction::unsupported(std::string type_name) {
  OpenSimFunction f;
  f.kind_ = Kind::Unsupported;
  f.type_name_ = std::move(type_name);
  return f;
}

OpenSimFunction OpenSimFunction::scaled(double scale) const {
  OpenSimFunction f = *this;
  f.scale_ *= scale;
  return f;
}

double OpenSimFunction::spline(double x, bool derivative) const {
  const std::size_t n = x_.size();
  // Beyond the knots: the line through the end knot with the end slope (as OpenSim extrapolates).
  if (x < x_.front()) return derivative ? b_.front() : y_.front() + (x - x_.front()) * b_.front();
  if (x > x_.back()) return derivative ? b_.back() : y_.back() + (x - x_.back()) * b_.back();
  const std::size_t i =
      std::min<std::size_t>(static_cast<std::size_t>(std::upper_bound(x_.begin(), x_.end(), x) - x_.begin()), n - 1) - 1;
  const double h = x - x_[i];
  if (n == 2) return derivative ? b_[0] : y_[0] + h * b_[0];
  if (derivative) return b_[i] + h * (2.0 * c_[i] + 3.0 * h * d_[i]);
  return y_[i] + h * (b_[i] + h * (c_[i] + h * d_[i]));
}

double OpenSimFunction::value(double x) const {
  switch (kind_) {
    case Kind::Constant: return scale_ * coefficients_[0];
    case Kind::Linear: return scale_ * (coefficients_[0] * x + coefficients_[1]);
    case Kind::Polynomial: {
      double v = 0.0;
      for (double c : coefficients_) v = v * x + c;
      return scale_ * v;
    }
    case Kind::SimmSpline: return scale_ * spline(x, false);
    case Kind::Unsupported: break;
  }
  throw std::runtime_error("OpenSim function '" + type_name_ + "' is not supported");
}

double OpenSimFunction::derivative(double x) const {
  switch (kind_) {
    case Kind::Constant: return 0.0;
    case Kind::Linear: return scale_ * coefficients_[0];
    case Kind::Polynomial: {
      double v = 0.0;
      const std::size_t degree = coefficients_.size() - 1;
      for (std::size_t k = 0; k < degree; ++k) v = v * x + static_cast<double>(degree - k) * coefficients_[k];
      return scale_ * v;
    }
    case Kind::SimmSpline: return scale_ * spline(x, true);
    case Kind::Unsupported: break;
  }
  throw std::runtime_error("OpenSim function '" + type_name_ + "' is not supported");
}

}  // namespace flatsos::plugin
