#include "flatsos/plugin/io/excitation_file.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>

#include "flatsos/plugin/io/sto_file.hpp"

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
// Maps header columns to muscles (labels through `muscle_of_label`), checks rows and builds the
// signals; `fail(row, what)` names the place (row index into `rows`, -1: the header).
template <class Fail>
std::vector<std::shared_ptr<const ExcitationSignal>> signals_from_table(
    const std::vector<std::string>& header, const std::vector<std::vector<double>>& rows,
    const std::vector<std::string>& muscle_names, const std::function<std::string(const std::string&)>& muscle_of_label,
    const Fail& fail) {
  if (header.empty() || header[0] != "time") fail(-1, "the first column must be 'time'");
  std::vector<int> column_of_muscle(muscle_names.size(), -1);
  for (std::size_t c = 1; c < header.size(); ++c) {
    const std::string name = muscle_of_label(header[c]);
    std::size_t j = 0;
    while (j < muscle_names.size() && muscle_names[j] != name) ++j;
    if (j == muscle_names.size()) fail(-1, "unknown muscle column '" + header[c] + "'");
    if (column_of_muscle[j] >= 0) fail(-1, "duplicate column '" + header[c] + "'");
    column_of_muscle[j] = static_cast<int>(c);
  }
  for (std::size_t j = 0; j < muscle_names.size(); ++j)
    if (column_of_muscle[j] < 0) fail(-1, "no column for muscle '" + muscle_names[j] + "'");
  std::vector<double> times;
  std::vector<std::vector<double>> values(muscle_names.size());
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const auto& row = rows[r];
    const int at = static_cast<int>(r);
    for (std::size_t c = 0; c < row.size(); ++c)
      if (!std::isfinite(row[c])) fail(at, "column '" + header[c] + "' is not finite");
    if (!times.empty() && !(row[0] > times.back())) fail(at, "times must increase strictly");
    times.push_back(row[0]);
    for (std::size_t j = 0; j < muscle_names.size(); ++j) {
      const double n = row[static_cast<std::size_t>(column_of_muscle[j])];
      if (n < 0.0 || n > 1.0) fail(at, "excitation " + std::to_string(n) + " of '" + muscle_names[j] + "' is outside [0, 1]");
      values[j].push_back(n);
    }
  }
  if (times.empty()) fail(-1, "no data rows");
  std::vector<std::shared_ptr<const ExcitationSignal>> out;
  for (auto& v : values) out.push_back(std::make_shared<PiecewiseLinearSignal>(times, std::move(v)));
  return out;
}

}  // namespace

std::vector<std::shared_ptr<const ExcitationSignal>> read_excitation_csv(
    const std::string& path, const std::vector<std::string>& muscle_names) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("excitation file '" + path + "': cannot be opened");
  int line_no = 0;
  std::vector<int> row_lines;  // file line of each data row
  auto fail_at_line = [&](int line, const std::string& what) {
    throw std::runtime_error("excitation file '" + path + "' line " + std::to_string(line) + ": " + what);
  };
  std::string line;
  if (!std::getline(in, line)) fail_at_line(0, "empty file (expected a header 'time,<muscle>,...')");
  ++line_no;
  const auto header = split_csv_line(line);
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const auto cells = split_csv_line(line);
    if (cells.size() != header.size())
      fail_at_line(line_no, std::to_string(cells.size()) + " cells for " + std::to_string(header.size()) + " columns");
    std::vector<double> row;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      char* end = nullptr;
      const double v = std::strtod(cells[c].c_str(), &end);
      if (cells[c].empty() || *end != '\0')
        fail_at_line(line_no, "'" + cells[c] + "' in column '" + header[c] + "' is not a number");
      row.push_back(v);
    }
    rows.push_back(std::move(row));
    row_lines.push_back(line_no);
  }
  return signals_from_table(header, rows, muscle_names, [](const std::string& label) { return label; },
                            [&](int row, const std::string& what) {
                              fail_at_line(row < 0 ? 1 : row_lines[static_cast<std::size_t>(row)], what);
                            });
}

std::vector<std::shared_ptr<const ExcitationSignal>> read_excitation_sto(
    const std::string& path, const std::vector<std::string>& muscle_names) {
  StoTable table;
  try {
    table = read_sto(path);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(std::string("excitation file: ") + e.what());
  }
  // Moco names a muscle's control by its path, /forceset/<muscle>.
  const auto muscle_of_label = [](const std::string& label) {
    const std::string prefix = "/forceset/";
    return label.rfind(prefix, 0) == 0 ? label.substr(prefix.size()) : label;
  };
  return signals_from_table(table.columns, table.rows, muscle_names, muscle_of_label, [&](int row, const std::string& what) {
    throw std::runtime_error("excitation file '" + path + "'" +
                             (row < 0 ? std::string(": ") : " data row " + std::to_string(row + 1) + ": ") + what);
  });
}

std::vector<std::shared_ptr<const ExcitationSignal>> read_excitation_file(
    const std::string& path, const std::vector<std::string>& muscle_names) {
  const bool sto = path.size() >= 4 && path.compare(path.size() - 4, 4, ".sto") == 0;
  return sto ? read_excitation_sto(path, muscle_names) : read_excitation_csv(path, muscle_names);
}

}  // namespace flatsos::plugin
