#pragma once
// The inverse problem's speed: arm26 with the muscles MocoInverse's examples use (DeGroote-Fregly
// 2016, passive force ignored) along OpenSim's CMC tutorial motion (1 s, 121 frames), the
// flatness inverse problem beside the collocation reference along the same motion (on the arm
// unpennated, as that reference needs), each with its squared-excitation optimum.

#include <nlohmann/json.hpp>

namespace flatsos::bench {

/// Medians over `repetitions` solves (the import and the motion's processing done once).
nlohmann::json inverse_problem_timing(int repetitions);

}  // namespace flatsos::bench
