#pragma once
// The one wall-clock timer of the project. Every timing in a result is a `<stage>_seconds` field
// measured with it (steady clock, seconds as double).

#include <chrono>

namespace flatsos {

class Stopwatch {
 public:
  Stopwatch() : start_(Clock::now()) {}
  /// Seconds since construction or the last restart().
  double seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }
  void restart() { start_ = Clock::now(); }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_;
};

}  // namespace flatsos
