#pragma once
// What both model fuzzers do with an input: parse_model_json, then build the Simbody model and
// read its default state. The documented failures are the only ones allowed: parse_model_json
// throws ModelFileError, the model's constructor ModelFileError, std::invalid_argument or
// std::domain_error. Anything else (a crash, a sanitizer report, any other exception, which
// escapes and aborts) is a finding.
#include <stdexcept>
#include <string>
#include <utility>

#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/model/model_description.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace flatsos::fuzz {

inline void check_model_text(const std::string& text) {
  plugin::ModelDescription description;
  try {
    description = plugin::parse_model_json(text, "fuzz");
  } catch (const plugin::ModelFileError&) {
    return;
  }
  try {
    const plugin::MusculoskeletalModel model(std::move(description));
    const SimTK::State state = model.defaultState();
    (void)model.jointAngles(state);
  } catch (const std::invalid_argument&) {  // includes ModelFileError
  } catch (const std::domain_error&) {
  }
}

}  // namespace flatsos::fuzz
