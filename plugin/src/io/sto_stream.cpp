#include "flatsos/plugin/io/sto_stream.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace flatsos::plugin {

StoStream::StoStream(std::string path, StoTable header)
    : path_(std::move(path)),
      rows_path_(path_ + ".rows.tmp" + std::to_string(::getpid())),
      header_(std::move(header)) {
  header_.rows.clear();
  rows_file_ = std::fopen(rows_path_.c_str(), "wb");
  if (!rows_file_)
    throw std::runtime_error("cannot write '" + rows_path_ + "': " + std::strerror(errno));
}

StoStream::~StoStream() {
  if (!rows_file_) return;
  std::fclose(rows_file_);
  std::remove(rows_path_.c_str());
}

void StoStream::append(const std::vector<double>& row) {
  if (!rows_file_) throw std::runtime_error("'" + path_ + "': rows appended after finish()");
  if (row.size() != header_.columns.size())
    throw std::runtime_error("'" + path_ + "': row " + std::to_string(rows_) + " has " +
                             std::to_string(row.size()) + " values for " +
                             std::to_string(header_.columns.size()) + " columns");
  for (std::size_t c = 0; c < row.size(); ++c)
    std::fprintf(rows_file_, c ? "\t%.17g" : "%.17g",
                 row[c]);  // write_sto's precision: round trips
  std::fputc('\n', rows_file_);
  ++rows_;
}

void StoStream::finish() {
  if (!rows_file_) throw std::runtime_error("'" + path_ + "': finished twice");
  const bool written = std::fflush(rows_file_) == 0 && !std::ferror(rows_file_);
  std::fclose(rows_file_);
  rows_file_ = nullptr;
  if (!written) {
    std::remove(rows_path_.c_str());
    throw std::runtime_error("writing the rows of '" + path_ + "' failed");
  }
  // The header needs the row count: the header, then the rows copied after it in chunks (a long
  // run's rows may be many megabytes), renamed into place.
  const std::string whole_path = path_ + ".tmp" + std::to_string(::getpid());
  bool copied = false;
  {
    std::ifstream rows(rows_path_, std::ios::binary);
    std::ofstream whole(whole_path, std::ios::binary | std::ios::trunc);
    whole << sto_header(header_, static_cast<std::size_t>(rows_));
    if (rows_ > 0) whole << rows.rdbuf();
    whole.flush();
    copied = rows && whole.good();
  }
  std::remove(rows_path_.c_str());
  if (!copied || std::rename(whole_path.c_str(), path_.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(whole_path.c_str());
    throw std::runtime_error("cannot write '" + path_ + "': " + why);
  }
}

}  // namespace flatsos::plugin
