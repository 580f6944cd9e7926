#pragma once
// One column of a state table by its OpenSim label, checked to exist (a missing column fails
// the test and gives NaN values).
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "flatsos/plugin/io/sto_file.hpp"

namespace flatsos::test {

inline std::vector<double> column(const plugin::StoTable& table, const std::string& label) {
  const int c = table.columnIndex(label);
  EXPECT_GE(c, 0) << "missing column " << label;
  std::vector<double> out;
  for (const auto& row : table.rows) out.push_back(c >= 0 ? row.at(static_cast<std::size_t>(c)) : NAN);
  return out;
}

}  // namespace flatsos::test
