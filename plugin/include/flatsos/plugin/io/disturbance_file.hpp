#pragma once
// An external disturbance on the joints, as a table of steps: each row's generalized forces
// (N m on a pin, N along a slider) act from its time until the next row's (none before the
// first row). Given as an OpenSim storage file (a "time" column and one column per joint,
// named by its coordinate or by the joint; joints without a column get none) or as rows.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace flatsos::plugin {

/// One external torque per joint from rows of (times_s[k], forces.row(k)) (forces: rows x
/// joints). Throws std::invalid_argument naming the problem for a wrong number of columns, times
/// that are not finite and strictly increasing, or a value that is not finite.
std::vector<ExternalJointTorque> disturbance_torques(const ModelDescription& model, const std::vector<double>& times_s,
                                                     const Eigen::MatrixXd& forces);

/// The same from a storage file. Throws std::runtime_error naming the file for a malformed
/// table, and std::invalid_argument naming the column for one that names no joint or
/// coordinate, or a table in degrees (forces have no angles).
std::vector<ExternalJointTorque> read_disturbance_file(const ModelDescription& model, const std::string& file);

}  // namespace flatsos::plugin
