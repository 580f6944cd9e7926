#include "flatsos/planner/step_time_histogram.hpp"

#include <algorithm>
#include <cmath>

namespace flatsos::planner {

namespace {
const double kLogSpan = std::log(StepTimeHistogram::kHighest_s / StepTimeHistogram::kLowest_s);
}

void StepTimeHistogram::add(double seconds) {
  const double position = std::log(std::max(seconds, kLowest_s) / kLowest_s) / kLogSpan * kBins;
  const int bin = std::isfinite(position) ? std::clamp(static_cast<int>(position), 0, kBins - 1) : kBins - 1;
  ++bins_[static_cast<std::size_t>(bin)];
  ++count_;
}

double StepTimeHistogram::quantile(double fraction) const {
  if (count_ == 0) return 0.0;
  const auto rank = static_cast<long>(std::ceil(std::clamp(fraction, 0.0, 1.0) * static_cast<double>(count_)));
  long seen = 0;
  int bin = 0;
  for (; bin < kBins - 1; ++bin) {
    seen += bins_[static_cast<std::size_t>(bin)];
    if (seen >= std::max(rank, 1L)) break;
  }
  return kLowest_s * std::exp((bin + 0.5) / kBins * kLogSpan);
}

}  // namespace flatsos::planner
