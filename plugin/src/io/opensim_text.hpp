#pragma once
// The text of OpenSim's XML values, shared by the readers of .osim and FunctionBasedPathSet files.

#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace flatsos::plugin::opensim_text {

// "/jointset/hip_r/hip_flexion_r" -> "hip_flexion_r".
inline std::string last_component(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// Whitespace-separated words.
inline std::vector<std::string> words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

// The whole word as a finite number, or nothing.
inline std::optional<double> finite_number(const std::string& word) {
  std::size_t used = 0;
  double value = NAN;
  try {
    value = std::stod(word, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (used != word.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

// The whole file as text, or nothing when it cannot be opened.
inline std::optional<std::string> file_text(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace flatsos::plugin::opensim_text
