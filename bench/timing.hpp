#pragma once
// Timing helpers of the benchmarks: wall-clock repetitions and their summary in JSON.
#include <algorithm>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "example_support.hpp"
#include "flatsos/plugin/stopwatch.hpp"

namespace flatsos::bench {

/// Median, min, max and count of `v`, each times `scale` (e.g. 1e3 for ms), with the unit.
inline nlohmann::json stats(std::vector<double> v, double scale, const std::string& unit) {
  std::sort(v.begin(), v.end());
  return {{"median", scale * examples::median(v)}, {"min", scale * v.front()}, {"max", scale * v.back()},
          {"samples", v.size()}, {"unit", unit}};
}

/// Wall seconds of `reps` calls of f.
template <class F>
std::vector<double> repeat(int reps, F f) {
  std::vector<double> out;
  for (int i = 0; i < reps; ++i) {
    const Stopwatch wall;
    f();
    out.push_back(wall.seconds());
  }
  return out;
}

}  // namespace flatsos::bench
