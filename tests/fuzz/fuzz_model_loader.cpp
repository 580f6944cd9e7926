// libFuzzer target for the model loader (FLATSOS_FUZZ=ON, clang; see CMakeLists.txt here).
// Arbitrary bytes go to parse_model_json; a description that parses is built into a Simbody
// model. The documented failures are the only ones allowed: parse_model_json throws
// ModelFileError, the model's constructor ModelFileError, std::invalid_argument or
// std::domain_error. Anything else (a crash, a sanitizer report, any other exception, which
// escapes here and aborts) is a finding.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>

#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/model/model_description.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  flatsos::plugin::ModelDescription description;
  try {
    description = flatsos::plugin::parse_model_json(text, "fuzz");
  } catch (const flatsos::plugin::ModelFileError&) {
    return 0;
  }
  try {
    const flatsos::plugin::MusculoskeletalModel model(std::move(description));
    const SimTK::State state = model.defaultState();
    (void)model.jointAngles(state);
  } catch (const std::invalid_argument&) {  // includes ModelFileError
  } catch (const std::domain_error&) {
  }
  return 0;
}
