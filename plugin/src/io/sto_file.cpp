#include "flatsos/plugin/io/sto_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace flatsos::plugin {

int StoTable::columnIndex(const std::string& label) const {
  for (std::size_t i = 0; i < columns.size(); ++i)
    if (columns[i] == label) return static_cast<int>(i);
  return -1;
}

std::vector<double> StoTable::column(const std::string& label) const {
  const int c = columnIndex(label);
  if (c < 0) throw std::runtime_error("table '" + name + "' has no column '" + label + "'");
  std::vector<double> out;
  out.reserve(rows.size());
  for (const auto& r : rows) out.push_back(r[static_cast<std::size_t>(c)]);
  return out;
}

std::string StoTable::metadataValue(const std::string& key) const {
  for (const auto& [k, v] : metadata)
    if (k == key) return v;
  return "";
}

void write_file_atomically(const std::string& path, const std::string& contents) {
  const std::string tmp = path + ".tmp" + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write '" + tmp + "': " + std::strerror(errno));
    out << contents;
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw std::runtime_error("writing '" + tmp + "' failed");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(tmp.c_str());
    throw std::runtime_error("cannot move '" + tmp + "' to '" + path + "': " + why);
  }
}

std::string sto_header(const StoTable& t, std::size_t rows) {
  std::ostringstream out;
  out << t.name << "\nversion=1\nnRows=" << rows << "\nnColumns=" << t.columns.size()
      << "\ninDegrees=" << (t.in_degrees ? "yes" : "no") << '\n';
  for (const auto& [k, v] : t.metadata) out << k << '=' << v << '\n';
  out << "endheader\n";
  for (std::size_t c = 0; c < t.columns.size(); ++c) out << (c ? "\t" : "") << t.columns[c];
  out << '\n';
  return out.str();
}

void write_sto(const std::string& path, const StoTable& t) {
  std::ostringstream out;
  out << sto_header(t, t.rows.size()) << std::setprecision(std::numeric_limits<double>::max_digits10);
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    if (t.rows[r].size() != t.columns.size())
      throw std::runtime_error("write_sto '" + path + "': row " + std::to_string(r) + " has " +
                               std::to_string(t.rows[r].size()) + " values for " +
                               std::to_string(t.columns.size()) + " columns");
    for (std::size_t c = 0; c < t.rows[r].size(); ++c) out << (c ? "\t" : "") << t.rows[r][c];
    out << '\n';
  }
  write_file_atomically(path, out.str());
}

StoTable read_sto(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open '" + path + "'");
  StoTable t;
  std::string line;
  int line_no = 0;
  auto fail = [&](const std::string& what) {
    throw std::runtime_error("'" + path + "' line " + std::to_string(line_no) + ": " + what);
  };
  bool header_done = false;
  while (std::getline(in, line)) {
    ++line_no;
    if (line_no == 1 && line.find('=') == std::string::npos) {
      t.name = line;
      continue;
    }
    if (line == "endheader") {
      header_done = true;
      break;
    }
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;  // free text is allowed in headers
    const std::string key = line.substr(0, eq);
    if (key == "inDegrees") t.in_degrees = line.substr(eq + 1) == "yes";
    if (key != "version" && key != "nRows" && key != "nColumns" && key != "inDegrees")
      t.metadata.emplace_back(key, line.substr(eq + 1));
  }
  if (!header_done) fail("no 'endheader' line");
  if (!std::getline(in, line)) fail("no column labels after 'endheader'");
  ++line_no;
  std::istringstream labels(line);
  for (std::string label; std::getline(labels, label, '\t');) t.columns.push_back(label);
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty()) continue;
    std::vector<double> row;
    std::istringstream cells(line);
    for (std::string cell; std::getline(cells, cell, '\t');) {
      char* end = nullptr;
      const double v = std::strtod(cell.c_str(), &end);
      if (end == cell.c_str() || *end != '\0') fail("'" + cell + "' is not a number");
      row.push_back(v);
    }
    if (row.size() != t.columns.size())
      fail(std::to_string(row.size()) + " values for " + std::to_string(t.columns.size()) + " columns");
    t.rows.push_back(std::move(row));
  }
  return t;
}

}  // namespace flatsos::plugin
