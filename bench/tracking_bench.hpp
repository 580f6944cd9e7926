#pragma once
// Tracking's speed: arm26 as downloaded (OpenSim 2.x's muscles, fitted paths) following OpenSim's
// CMC tutorial motion (1 s, 20 control periods): the controller's step per period and the closed
// loop (controller and Simbody plant) per second of motion, beside the tracking error.

#include <nlohmann/json.hpp>

namespace flatsos::bench {

/// Medians over `repetitions` runs (the import and the motion's processing done once).
nlohmann::json tracking_timing(int repetitions);

}  // namespace flatsos::bench
