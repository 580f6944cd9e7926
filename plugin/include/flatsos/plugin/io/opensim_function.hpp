#pragma once
// The one-argument functions OpenSim's joints and constraints use to map a coordinate to a
// rotation angle, a translation or another coordinate (CustomJoint's TransformAxis,
// CoordinateCouplerConstraint): Constant, LinearFunction, PolynomialFunction, SimmSpline, and a
// MultiplierFunction scaling any of them. Values and first derivatives, as OpenSim evaluates them.

#include <string>
#include <vector>

namespace flatsos::plugin {

class OpenSimFunction {
 public:
  enum class Kind {
    Constant,     ///< coefficients = {value}
    Linear,       ///< coefficients = {slope, intercept}
    Polynomial,   ///< coefficients highest power first (SimTK::Function::Polynomial)
    SimmSpline,   ///< knots x, y: Forsythe-Malcolm-Moler cubic spline, linear beyond the ends
    Unsupported,  ///< another OpenSim function; evaluating it throws, naming `type_name`
  };

  /// The identity (a LinearFunction 1 x + 0), OpenSim's default for an axis with one coordinate.
  static OpenSimFunction identity();
  static OpenSimFunction constant(double value);
  static OpenSimFunction linear(double slope, double intercept);
  static OpenSimFunction polynomial(std::vector<double> coefficients_highest_first);
  /// Throws std::invalid_argument unless x has at least 2 strictly increasing knots and y as many.
  static OpenSimFunction simmSpline(std::vector<double> x, std::vector<double> y);
  static OpenSimFunction unsupported(std::string type_name);

  /// The function times `scale` (OpenSim's MultiplierFunction).
  OpenSimFunction scaled(double scale) const;

  Kind kind() const { return kind_; }
  const std::string& typeName() const { return type_name_; }
  /// f(x) and f'(x). Throw std::runtime_error for an Unsupported function.
  double value(double x) const;
  double derivative(double x) const;

 private:
  Kind kind_ = Kind::Constant;
  std::string type_name_ = "Constant";
  double scale_ = 1.0;
  std::vector<double> coefficients_{0.0};
  std::vector<double> x_, y_, b_, c_, d_;  // spline knots and the cubic's coefficients per knot
  double spline(double x, bool derivative) const;
};

}  // namespace flatsos::plugin
