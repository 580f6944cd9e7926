#pragma once
// Excitation inputs of a muscle that vary with time: a muscle whose state holds a signal reads
// its excitation n(t) from it at every integrator stage, so open-loop schedules and the
// receding-horizon controller's per-interval plans are applied exactly, not zero-order held.

#include <array>
#include <memory>
#include <vector>

namespace flatsos::plugin {

/// A scalar function of time (s) giving a neural excitation. Implementations must be
/// immutable after construction (the same object may be shared by many States).
class ExcitationSignal {
 public:
  virtual ~ExcitationSignal() = default;
  virtual double value(double time_s) const = 0;
};

/// A polynomial excitation over one interval, held by value in a muscle's State:
///   n(t) = sum_k c_k s^k,  s = clamp((t - start_time_s) / duration_s, 0, 1),
/// so it is held at its ends. Setting one allocates nothing (a controller's inner loop writes
/// one per muscle per period) and every copy of the State keeps its own. A constant excitation
/// is the piece with one coefficient.
struct ExcitationPolynomial {
  static constexpr int kMaxCoefficients = 8;
  std::array<double, kMaxCoefficients> coefficients{};  ///< c_0 .. c_{count-1}, ascending powers of s
  int count = 1;
  double start_time_s = 0.0;
  double duration_s = 1.0;

  static ExcitationPolynomial constant(double excitation);
  double value(double time_s) const;
  /// Throws std::invalid_argument unless 1 <= count <= kMaxCoefficients, the used coefficients
  /// and the start are finite and the duration is finite and > 0.
  void validate() const;
};

/// A muscle's excitation input as its State holds it: the held piece, or a signal that, when
/// set, overrides the piece.
struct ExcitationInput {
  ExcitationPolynomial piece;
  std::shared_ptr<const ExcitationSignal> signal;
};

/// `input` late by `delay_s`: its value at t is the given input's at t - delay_s. A piece is
/// moved (no allocation); a signal is wrapped in a new one.
ExcitationInput delayed(const ExcitationInput& input, double delay_s);

/// Linear interpolation between samples; held constant before the first and after the last.
class PiecewiseLinearSignal final : public ExcitationSignal {
 public:
  /// Throws std::invalid_argument unless times are finite and strictly increasing, values
  /// finite, and both have the same non-zero size.
  PiecewiseLinearSignal(std::vector<double> times_s, std::vector<double> values);
  double value(double time_s) const override;

 private:
  std::vector<double> times_s_;
  std::vector<double> values_;
};

/// Each value held from its time until the next one's; 0 before the first (a disturbance given
/// as a table of steps). Throws as PiecewiseLinearSignal does.
class PiecewiseConstantSignal final : public ExcitationSignal {
 public:
  PiecewiseConstantSignal(std::vector<double> times_s, std::vector<double> values);
  double value(double time_s) const override;

 private:
  std::vector<double> times_s_;
  std::vector<double> values_;
};

}  // namespace flatsos::plugin
