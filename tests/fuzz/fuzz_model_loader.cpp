// libFuzzer target for the model loader on arbitrary bytes (FLATSOS_FUZZ=ON, clang; see
// CMakeLists.txt here): what model_check.hpp allows, nothing else.
#include <cstddef>
#include <cstdint>
#include <string>

#include "model_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  flatsos::fuzz::check_model_text(std::string(reinterpret_cast<const char*>(data), size));
  return 0;
}
