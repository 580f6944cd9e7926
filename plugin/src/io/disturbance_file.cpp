#include "flatsos/plugin/io/disturbance_file.hpp"

#include <cmath>
#include <memory>
#include <stdexcept>

#include "flatsos/plugin/force/excitation_signal.hpp"
#include "flatsos/plugin/io/sto_file.hpp"

namespace flatsos::plugin {

std::vector<ExternalJointTorque> disturbance_torques(const ModelDescription& model, const std::vector<double>& times_s,
                                                     const Eigen::MatrixXd& forces) {
  const int n = model.numJoints();
  if (forces.cols() != n || forces.rows() != static_cast<Eigen::Index>(times_s.size()) || times_s.empty())
    throw std::invalid_argument("disturbance: need one row per time (" + std::to_string(times_s.size()) +
                                " times, " + std::to_string(forces.rows()) + " rows) and one column per joint (" +
                                std::to_string(n) + ", got " + std::to_string(forces.cols()) + ")");
  std::vector<ExternalJointTorque> torques;
  for (int i = 0; i < n; ++i) {
    const Eigen::VectorXd column = forces.col(i);
    if (!column.allFinite())
      throw std::invalid_argument("disturbance on joint '" + model.joints[static_cast<std::size_t>(i)].name +
                                  "': a value is not finite");
    if (column.isZero(0.0)) continue;
    try {
      torques.push_back({i, std::make_shared<const PiecewiseConstantSignal>(
                                times_s, std::vector<double>(column.data(), column.data() + column.size()))});
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("disturbance: ") + e.what());
    }
  }
  return torques;
}

std::vector<ExternalJointTorque> read_disturbance_file(const ModelDescription& model, const std::string& file) {
  const StoTable table = read_sto(file);
  if (table.in_degrees)
    throw std::invalid_argument(file + ": a disturbance is in N m (N along a slider), not degrees (inDegrees=yes)");
  if (table.columnIndex("time") != 0) throw std::invalid_argument(file + ": the first column must be 'time'");
  std::vector<double> times_s = table.column("time");
  Eigen::MatrixXd forces = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(times_s.size()), model.numJoints());
  for (std::size_t c = 1; c < table.columns.size(); ++c) {
    int joint = -1;
    for (int i = 0; i < model.numJoints(); ++i) {
      const JointDescription& d = model.joints[static_cast<std::size_t>(i)];
      if (table.columns[c] == d.name || table.columns[c] == d.coordinateName()) joint = i;
    }
    if (joint < 0)
      throw std::invalid_argument(file + ": column '" + table.columns[c] + "' names no joint or coordinate of model '" +
                                  model.name + "'");
    for (std::size_t r = 0; r < times_s.size(); ++r) forces(static_cast<Eigen::Index>(r), joint) = table.rows[r][c];
  }
  try {
    return disturbance_torques(model, times_s, forces);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(file + ": " + e.what());
  }
}

}  // namespace flatsos::plugin
