#pragma once
// Excitation inputs of a muscle that vary with time: a muscle whose state holds a signal reads
// its excitation n(t) from it at every integrator stage, so open-loop schedules and the
// receding-horizon controller's per-interval plans are applied exactly, not zero-order held.

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

}  // namespace flatsos::plugin
