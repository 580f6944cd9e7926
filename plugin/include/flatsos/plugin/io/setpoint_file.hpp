#pragma once
// Set points over time as an OpenSim storage file: a "time" column and one column per joint,
// named by its coordinate or by the joint; each row's angles are the target from its time on.
// Angles in degrees when the header says inDegrees=yes (a slider's in m either way).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "flatsos/plugin/model/model_description.hpp"

namespace flatsos::plugin {

struct SetpointRows {
  std::vector<double> times_s;
  std::vector<Eigen::VectorXd> targets_q_rad;  ///< one per time, one angle per joint (rad, m)
};

/// Throws std::runtime_error naming the file for a malformed table, std::invalid_argument naming
/// the file and column for a column that names no joint, a joint without a column, or a value
/// that is not finite.
SetpointRows read_setpoint_file(const ModelDescription& model, const std::string& file);

}  // namespace flatsos::plugin
