#pragma once
// Dual numbers x + e x' (e^2 = 0) for exact derivatives by forward-mode differentiation, nestable:
// Dual<Dual<double>> carries two independent infinitesimals and their product, which gives a
// function's second derivative along a curve (the torque jets along a joint motion), and one
// more level gives the derivatives of those with respect to the motion. Only what the pin-tree
// inverse dynamics needs: arithmetic, sin, cos, and Eigen's NumTraits so that Eigen's fixed-size
// vectors and matrices can hold them.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <cmath>

#include <Eigen/Core>

namespace flatsos::plugin {

template <class T>
struct Dual {
  T value{};
  T derivative{};  ///< the coefficient of e

  Dual() = default;
  Dual(double v) : value(v), derivative(0.0) {}  // NOLINT: constants mix with duals implicitly
  Dual(const T& v, const T& d) : value(v), derivative(d) {}

  Dual& operator+=(const Dual& b) { value += b.value; derivative += b.derivative; return *this; }
  Dual& operator-=(const Dual& b) { value -= b.value; derivative -= b.derivative; return *this; }
  Dual& operator*=(const Dual& b) { return *this = *this * b; }
  Dual& operator/=(const Dual& b) { return *this = *this / b; }

  friend Dual operator+(const Dual& a, const Dual& b) { return {a.value + b.value, a.derivative + b.derivative}; }
  friend Dual operator-(const Dual& a, const Dual& b) { return {a.value - b.value, a.derivative - b.derivative}; }
  friend Dual operator-(const Dual& a) { return {-a.value, -a.derivative}; }
  friend Dual operator*(const Dual& a, const Dual& b) {
    return {a.value * b.value, a.value * b.derivative + a.derivative * b.value};
  }
  friend Dual operator/(const Dual& a, const Dual& b) {
    const T q = a.value / b.value;
    return {q, (a.derivative - q * b.derivative) / b.value};
  }
  friend Dual sin(const Dual& a) {
    using std::cos;
    using std::sin;
    return {sin(a.value), a.derivative * cos(a.value)};
  }
  friend Dual cos(const Dual& a) {
    using std::cos;
    using std::sin;
    return {cos(a.value), -(a.derivative * sin(a.value))};
  }
  // Comparisons on the value: what Eigen's generic code may ask of a scalar.
  friend bool operator==(const Dual& a, const Dual& b) { return a.value == b.value && a.derivative == b.derivative; }
  friend bool operator!=(const Dual& a, const Dual& b) { return !(a == b); }
};

/// The plain value of a (nested) dual number: for branches, which follow the value.
inline double primal(double x) { return x; }
template <class T>
double primal(const Dual<T>& x) {
  return primal(x.value);
}

}  // namespace flatsos::plugin

namespace Eigen {
template <class T>
struct NumTraits<flatsos::plugin::Dual<T>> : GenericNumTraits<flatsos::plugin::Dual<T>> {
  using Real = flatsos::plugin::Dual<T>;
  using NonInteger = flatsos::plugin::Dual<T>;
  using Nested = flatsos::plugin::Dual<T>;
  using Literal = flatsos::plugin::Dual<T>;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 1,
    ReadCost = 2 * NumTraits<T>::ReadCost,
    AddCost = 2 * NumTraits<T>::AddCost,
    MulCost = 3 * NumTraits<T>::MulCost,
  };
  static inline Real epsilon() { return Real(NumTraits<double>::epsilon()); }
  static inline Real dummy_precision() { return Real(NumTraits<double>::dummy_precision()); }
  static inline int digits10() { return NumTraits<double>::digits10(); }
};
}  // namespace Eigen
