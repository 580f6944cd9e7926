#include "flatsos/plugin/io/excitation_file.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace flatsos::plugin {

namespace {
std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) {
    const auto b = cell.find_first_not_of(" \t\r");
    const auto e = cell.find_last_not_of(" \t\r");
    cells.push_back(b == std::string::npos ? "" : cell.substr(b, e - b + 1));
  }
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}
}  // namespace

std::vector<std::shared_ptr<const ExcitationSignal>> read_excitation_csv(
    const std::string& path, const std::vector<std::string>& muscle_names) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("excitation file '" + path + "': cannot be opened");
  int line_no = 0;
  auto fail = [&](const std::string& what) {
    throw std::runtime_error("excitation file '" + path + "' line " + std::to_string(line_no) + ": " + what);
  };
  std::string line;
  if (!std::getline(in, line)) fail("empty file (expected a header 'time,<muscle>,...')");
  ++line_no;
  const auto header = split_csv_line(line);
  if (header.empty() || header[0] != "time") fail("the first column must be 'time'");
  std::vector<int> column_of_muscle(muscle_names.size(), -1);
  for (std::size_t c = 1; c < header.size(); ++c) {
    std::size_t j = 0;
    while (j < muscle_names.size() && muscle_names[j] != header[c]) ++j;
    if (j == muscle_names.size()) fail("unknown muscle column '" + header[c] + "'");
    if (column_of_muscle[j] >= 0) fail("duplicate column '" + header[c] + "'");
    column_of_muscle[j] = static_cast<int>(c);
  }
  for (std::size_t j = 0; j < muscle_names.size(); ++j)
    if (column_of_muscle[j] < 0) fail("no column for muscle '" + muscle_names[j] + "'");

  std::vector<double> times;
  std::vector<std::vector<double>> values(muscle_names.size());
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const auto cells = split_csv_line(line);
    if (cells.size() != header.size())
      fail(std::to_string(cells.size()) + " cells for " + std::to_string(header.size()) + " columns");
    std::vector<double> row;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      char* end = nullptr;
      const double v = std::strtod(cells[c].c_str(), &end);
      if (cells[c].empty() || *end != '\0') fail("'" + cells[c] + "' in column '" + header[c] + "' is not a number");
      if (!std::isfinite(v)) fail("column '" + header[c] + "' is not finite");
      row.push_back(v);
    }
    if (!times.empty() && !(row[0] > times.back())) fail("times must increase strictly");
    times.push_back(row[0]);
    for (std::size_t j = 0; j < muscle_names.size(); ++j) {
      const double n = row[static_cast<std::size_t>(column_of_muscle[j])];
      if (n < 0.0 || n > 1.0)
        fail("excitation " + std::to_string(n) + " of '" + muscle_names[j] + "' is outside [0, 1]");
      values[j].push_back(n);
    }
  }
  if (times.empty()) fail("no data rows");
  std::vector<std::shared_ptr<const ExcitationSignal>> out;
  for (auto& v : values) out.push_back(std::make_shared<PiecewiseLinearSignal>(times, std::move(v)));
  return out;
}

}  // namespace flatsos::plugin
