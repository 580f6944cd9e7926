#pragma once
// A storage (.sto) file written row by row, for runs too long to keep their tables in memory:
// the rows go to a temporary file beside the target as they come, and finish() puts the header
// (with its row count) before them and renames the whole into place. A run stopped early, by a
// signal for instance, that calls finish() leaves a complete file of the rows it wrote; one that
// dies before leaves the previous file or none, never half a file.

#include <cstdio>
#include <string>
#include <vector>

#include "flatsos/plugin/io/sto_file.hpp"

namespace flatsos::plugin {

class StoStream {
 public:
  /// `header`: the table's name, metadata, columns and inDegrees flag (its rows are ignored).
  /// Throws std::runtime_error when the folder cannot be written.
  StoStream(std::string path, StoTable header);
  ~StoStream();  ///< without finish(): removes the temporary file, the target is untouched
  StoStream(const StoStream&) = delete;
  StoStream& operator=(const StoStream&) = delete;

  /// Appends one row (as many values as columns; std::runtime_error otherwise, naming the file).
  void append(const std::vector<double>& row);
  long rows() const { return rows_; }
  /// The header to come (its metadata may change until finish()).
  StoTable& header() { return header_; }
  /// Writes the file in place (atomically). Throws std::runtime_error on a write error.
  void finish();

 private:
  std::string path_, rows_path_;
  StoTable header_;
  std::FILE* rows_file_ = nullptr;
  long rows_ = 0;
};

}  // namespace flatsos::plugin
