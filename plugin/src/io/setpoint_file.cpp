#include "flatsos/plugin/io/setpoint_file.hpp"

#include <cmath>
#include <stdexcept>

#include "flatsos/plugin/io/sto_file.hpp"

namespace flatsos::plugin {

SetpointRows read_setpoint_file(const ModelDescription& model, const std::string& file) {
  const StoTable table = read_sto(file);
  if (table.columnIndex("time") != 0)
    throw std::invalid_argument(file + ": the first column must be 'time'");
  const int n = model.numJoints();
  std::vector<int> column_of(static_cast<std::size_t>(n), -1);
  for (std::size_t c = 1; c < table.columns.size(); ++c) {
    int joint = -1;
    for (int i = 0; i < n; ++i) {
      const JointDescription& d = model.joints[static_cast<std::size_t>(i)];
      if (table.columns[c] == d.name || table.columns[c] == d.coordinateName()) joint = i;
    }
    if (joint < 0)
      throw std::invalid_argument(file + ": column '" + table.columns[c] +
                                  "' names no joint or coordinate of model '" + model.name + "'");
    column_of[static_cast<std::size_t>(joint)] = static_cast<int>(c);
  }
  for (int i = 0; i < n; ++i)
    if (column_of[static_cast<std::size_t>(i)] < 0)
      throw std::invalid_argument(file + ": no column for joint '" +
                                  model.joints[static_cast<std::size_t>(i)].name +
                                  "' (a set point gives every joint's target)");
  SetpointRows out;
  for (const auto& row : table.rows) {
    Eigen::VectorXd target(n);
    for (int i = 0; i < n; ++i) {
      const JointDescription& d = model.joints[static_cast<std::size_t>(i)];
      const double value = row[static_cast<std::size_t>(column_of[static_cast<std::size_t>(i)])];
      target[i] = table.in_degrees && !d.isSlider() ? value * M_PI / 180.0 : value;
    }
    if (!target.allFinite() || !std::isfinite(row[0]))
      throw std::invalid_argument(file + ": a value at time " + std::to_string(row[0]) +
                                  " is not finite");
    out.times_s.push_back(row[0]);
    out.targets_q_rad.push_back(std::move(target));
  }
  return out;
}

}  // namespace flatsos::plugin
