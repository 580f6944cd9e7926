#include "default_model.hpp"

#include <filesystem>

namespace flatsos::examples {

std::string default_model_path(const std::string& file) {
  namespace fs = std::filesystem;
  std::error_code error;
  // Linux: the running executable, symlinks resolved (argv[0] may be relative or on PATH).
  const fs::path exe = fs::canonical("/proc/self/exe", error);
  const fs::path bin = error ? fs::current_path() : exe.parent_path();
  return (bin.parent_path() / "share" / "flatsos" / "models" / file).lexically_normal().string();
}

}  // namespace flatsos::examples
