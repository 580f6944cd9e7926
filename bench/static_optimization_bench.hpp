#pragma once
// Static optimization's speed: arm26 as downloaded along OpenSim's tutorial motion (121 frames,
// 1 s), with the model's geometry paths (as OpenSim) and with its fitted polynomials, per frame
// and per second of motion, and the share of each frame's program.

#include <nlohmann/json.hpp>

namespace flatsos::bench {

/// Medians over `repetitions` runs of the whole tool (motion processing excluded: done once).
nlohmann::json static_optimization_timing(int repetitions);

}  // namespace flatsos::bench
