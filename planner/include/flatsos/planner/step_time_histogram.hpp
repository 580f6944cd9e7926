#pragma once
// A controller's step wall times in constant memory: a run of any length records every step
// without allocating, and its quantiles (median, 99th percentile) come to within 1 %.

#include <array>

namespace flatsos::planner {

/// 1000 logarithmic bins from 1e-7 s to 100 s, each 2.1 % wide; a time outside counts in the
/// first or the last bin.
class StepTimeHistogram {
 public:
  static constexpr int kBins = 1000;
  static constexpr double kLowest_s = 1e-7, kHighest_s = 100.0;

  void add(double seconds);
  long count() const { return count_; }
  /// The step time below which `fraction` (in (0, 1]) of the steps lie, as the geometric middle
  /// of its bin (within 1.05 % of the exact order statistic); 0 before any step.
  double quantile(double fraction) const;

 private:
  std::array<long, kBins> bins_{};
  long count_ = 0;
};

}  // namespace flatsos::planner
