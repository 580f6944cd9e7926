#pragma once
// How each stage of planning and control grows with the model: the flat-output map (with the
// library's choice of flat outputs where the model gives none), the open-loop plan of the
// model's scenario, the receding-horizon step split into its parts, and the closed loop, one
// model at a time, beside the targets for its size.
#include <string>

#include <nlohmann/json.hpp>

namespace flatsos::bench {

/// Times every stage on the model file's own scenarios ("open_loop", "receding_horizon");
/// `repetitions` of the open-loop plan and of the closed loop (medians reported).
nlohmann::json scaling_row(const std::string& model_path, int repetitions);

/// The rows' stages side by side, each as a multiple of the first row's (the smallest model).
nlohmann::json growth(const nlohmann::json& rows);

}  // namespace flatsos::bench
