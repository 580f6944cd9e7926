#pragma once
// Where the programs find their default model: <prefix>/share/flatsos/models next to the
// <prefix>/bin they run from. The build tree mirrors that layout (build/share/flatsos/models is
// copied from models/ at build time), so no path into the source tree is compiled in and an
// installed prefix can be moved.

#include <string>

namespace flatsos::examples {

/// <directory of the running program>/../share/flatsos/models/<file>, whether or not it exists
/// (the model loader names it when it does not).
std::string default_model_path(const std::string& file = "arm_richter_warner.json");

}  // namespace flatsos::examples
