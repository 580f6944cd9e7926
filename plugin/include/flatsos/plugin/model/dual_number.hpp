#pragma once
// Dual numbers x + e x' (e^2 = 0) for exact derivatives by forward-mode differentiation, nestable:
// Dual<Dual<double>> carries two independent infinitesimals and their product (second
// derivatives). TimeJet carries a function's first two derivatives along a curve (the torque jets
// along a joint motion); with dual numbers inside, it also gives the derivatives of those with
// respect to the motion. Only what the pin-tree inverse dynamics needs: arithmetic, sin, cos, and
// Eigen's NumTraits so that Eigen's fixed-size vectors and matrices can hold them.

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

/// A function of time t and its first two derivatives (f, f', f''), carried through arithmetic by
/// the product and chain rules: what Dual<Dual<T>> gives with both infinitesimals on the same
/// motion, in three entries instead of four ((fg)'' = f'' g + 2 f' g' + f g'' is six products of
/// T, the nested duals' is nine). The torque jets along a joint motion use it.
template <class T>
struct TimeJet {
  T value{}, rate{}, acceleration{};  ///< f, f', f''

  TimeJet() = default;
  TimeJet(double v) : value(v), rate(0.0), acceleration(0.0) {}  // NOLINT: constants mix implicitly
  TimeJet(const T& v, const T& d, const T& dd) : value(v), rate(d), acceleration(dd) {}

  TimeJet& operator+=(const TimeJet& b) {
    value += b.value;
    rate += b.rate;
    acceleration += b.acceleration;
    return *this;
  }
  TimeJet& operator-=(const TimeJet& b) {
    value -= b.value;
    rate -= b.rate;
    acceleration -= b.acceleration;
    return *this;
  }
  TimeJet& operator*=(const TimeJet& b) { return *this = *this * b; }
  TimeJet& operator/=(const TimeJet& b) { return *this = *this / b; }

  friend TimeJet operator+(const TimeJet& a, const TimeJet& b) {
    return {a.value + b.value, a.rate + b.rate, a.acceleration + b.acceleration};
  }
  friend TimeJet operator-(const TimeJet& a, const TimeJet& b) {
    return {a.value - b.value, a.rate - b.rate, a.acceleration - b.acceleration};
  }
  friend TimeJet operator-(const TimeJet& a) { return {-a.value, -a.rate, -a.acceleration}; }
  friend TimeJet operator*(const TimeJet& a, const TimeJet& b) {
    const T cross = a.rate * b.rate;
    return {a.value * b.value, a.value * b.rate + a.rate * b.value,
            a.value * b.acceleration + (cross + cross) + a.acceleration * b.value};
  }
  friend TimeJet operator/(const TimeJet& a, const TimeJet& b) {
    // a = q b, so a' = q' b + q b' and a'' = q'' b + 2 q' b' + q b''.
    const T q = a.value / b.value;
    const T q1 = (a.rate - q * b.rate) / b.value;
    const T twice = q1 * b.rate;
    return {q, q1, (a.acceleration - (twice + twice) - q * b.acceleration) / b.value};
  }
  friend TimeJet sin(const TimeJet& a) {
    using std::cos;
    using std::sin;
    const T s = sin(a.value), c = cos(a.value);
    return {s, c * a.rate, c * a.acceleration - s * (a.rate * a.rate)};
  }
  friend TimeJet cos(const TimeJet& a) {
    using std::cos;
    using std::sin;
    const T s = sin(a.value), c = cos(a.value);
    return {c, -(s * a.rate), -(s * a.acceleration) - c * (a.rate * a.rate)};
  }
  friend bool operator==(const TimeJet& a, const TimeJet& b) {
    return a.value == b.value && a.rate == b.rate && a.acceleration == b.acceleration;
  }
  friend bool operator!=(const TimeJet& a, const TimeJet& b) { return !(a == b); }
};

/// x times a constant: each entry scaled, where the product with the constant promoted to a jet
/// would multiply every pair of entries (a time jet of dual numbers: 6 products instead of 18).
inline double scaled(double x, double c) { return x * c; }
template <class T>
Dual<T> scaled(const Dual<T>& x, double c) {
  return {scaled(x.value, c), scaled(x.derivative, c)};
}
template <class T>
TimeJet<T> scaled(const TimeJet<T>& x, double c) {
  return {scaled(x.value, c), scaled(x.rate, c), scaled(x.acceleration, c)};
}

/// The plain value of a (nested) dual number or time jet: for branches, which follow the value.
inline double primal(double x) { return x; }
template <class T>
double primal(const Dual<T>& x) {
  return primal(x.value);
}
template <class T>
double primal(const TimeJet<T>& x) {
  return primal(x.value);
}

}  // namespace flatsos::plugin

namespace flatsos::plugin::detail {
// What Eigen asks of a scalar made of `Entries` values of T whose product takes `Products`
// products of T: a dual number 2 and 3, a time jet 3 and 6.
template <class Scalar, class T, int Entries, int Products>
struct JetNumTraits : Eigen::GenericNumTraits<Scalar> {
  using Real = Scalar;
  using NonInteger = Scalar;
  using Nested = Scalar;
  using Literal = Scalar;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 1,
    ReadCost = Entries * Eigen::NumTraits<T>::ReadCost,
    AddCost = Entries * Eigen::NumTraits<T>::AddCost,
    MulCost = Products * Eigen::NumTraits<T>::MulCost,
  };
  static inline Real epsilon() { return Real(Eigen::NumTraits<double>::epsilon()); }
  static inline Real dummy_precision() { return Real(Eigen::NumTraits<double>::dummy_precision()); }
  static inline int digits10() { return Eigen::NumTraits<double>::digits10(); }
};
}  // namespace flatsos::plugin::detail

namespace Eigen {
template <class T>
struct NumTraits<flatsos::plugin::Dual<T>>
    : flatsos::plugin::detail::JetNumTraits<flatsos::plugin::Dual<T>, T, 2, 3> {};
template <class T>
struct NumTraits<flatsos::plugin::TimeJet<T>>
    : flatsos::plugin::detail::JetNumTraits<flatsos::plugin::TimeJet<T>, T, 3, 6> {};
}  // namespace Eigen
