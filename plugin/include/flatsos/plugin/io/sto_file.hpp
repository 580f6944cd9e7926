#pragma once
// OpenSim-style storage (.sto) tables: a "key=value" header ending in "endheader", then a
// tab-separated table whose first column is time. OpenSim 4 and a spreadsheet read them.
// Writing is atomic: a temporary file in the same folder is renamed into place, so an
// interrupted run leaves the previous file or none, never half a file.

#include <string>
#include <utility>
#include <vector>

namespace flatsos::plugin {

struct StoTable {
  std::string name = "flatsos";                               ///< first header line
  std::vector<std::pair<std::string, std::string>> metadata;  ///< extra key=value lines
  std::vector<std::string> columns;                           ///< including "time" first
  std::vector<std::vector<double>> rows;
  /// The header's inDegrees flag: angles in the table are in degrees ("inDegrees=yes", as in
  /// OpenSim's .mot files); false when the flag is absent or "no".
  bool in_degrees = false;

  int columnIndex(const std::string& label) const;  ///< -1 when absent
  std::vector<double> column(const std::string& label) const;  ///< throws if absent
  std::string metadataValue(const std::string& key) const;     ///< "" when absent
};

/// Throws std::runtime_error when the folder cannot be written or a row has the wrong width.
void write_sto(const std::string& path, const StoTable& table);
/// The header of `table` for `rows` rows, through the column labels' line.
std::string sto_header(const StoTable& table, std::size_t rows);
/// Throws std::runtime_error naming the file and line on malformed input.
StoTable read_sto(const std::string& path);

/// Write text to path atomically (temporary file + rename). Throws std::runtime_error.
void write_file_atomically(const std::string& path, const std::string& contents);

}  // namespace flatsos::plugin
