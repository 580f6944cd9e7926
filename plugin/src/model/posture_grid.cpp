#include "flatsos/plugin/model/posture_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <stdexcept>

namespace flatsos::plugin {

void for_each_posture(const ModelDescription& model, const std::vector<int>& joints, long budget,
                      const std::function<void(const Eigen::VectorXd&)>& visit, const JointRanges& box) {
  if (!box.empty() && box.size() != model.joints.size())
    throw std::invalid_argument("posture grid: " + std::to_string(box.size()) + " ranges for " +
                                std::to_string(model.joints.size()) + " joints");
  const int k = static_cast<int>(joints.size());
  const int per_joint = std::max(2, static_cast<int>(std::floor(std::pow(static_cast<double>(budget), 1.0 / std::max(k, 1)))));
  std::vector<int> index(static_cast<std::size_t>(k), 0);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(model.numJoints());
  while (true) {
    for (int d = 0; d < k; ++d) {
      const auto joint = static_cast<std::size_t>(joints[static_cast<std::size_t>(d)]);
      const auto& r = box.empty() ? model.joints[joint].range_rad : box[joint];
      q[joints[static_cast<std::size_t>(d)]] = r[0] + (r[1] - r[0]) * index[static_cast<std::size_t>(d)] / (per_joint - 1);
    }
    visit(q);
    int d = 0;
    while (d < k && ++index[static_cast<std::size_t>(d)] == per_joint) index[static_cast<std::size_t>(d++)] = 0;
    if (d == k) return;
  }
}

std::string describe_posture(const ModelDescription& model, const std::vector<int>& joints, const Eigen::VectorXd& q) {
  std::string out;
  for (int i : joints) {
    if (!out.empty()) out += ", ";
    const JointDescription& joint = model.joints[static_cast<std::size_t>(i)];
    out += joint.name + " = " + std::to_string(q[i] * joint.displayPerSI()) + " " + joint.displayUnit();
  }
  return out;
}

std::string describe_posture(const ModelDescription& model, const Eigen::VectorXd& q) {
  std::vector<int> all(static_cast<std::size_t>(model.numJoints()));
  for (int i = 0; i < model.numJoints(); ++i) all[static_cast<std::size_t>(i)] = i;
  return describe_posture(model, all, q);
}

std::string describe_region(const ModelDescription& model, const JointRanges& box) {
  std::string out;
  char range[64];
  for (std::size_t i = 0; i < box.size() && i < model.joints.size(); ++i) {
    const JointDescription& joint = model.joints[i];
    std::snprintf(range, sizeof range, " %.3f .. %.3f ", box[i][0] * joint.displayPerSI(), box[i][1] * joint.displayPerSI());
    out += (out.empty() ? "" : ", ") + joint.name + range + joint.displayUnit();
  }
  return out;
}

std::vector<int> posture_dependent_joints(const ModelDescription& model) {
  std::set<int> joints;
  for (int j = 0; j < model.numMuscles(); ++j) {
    const muscles::MusculotendonPath path = model.musclePath(j);
    if (!path.hasConstantMomentArms()) joints.insert(path.crossedJoints().begin(), path.crossedJoints().end());
  }
  return {joints.begin(), joints.end()};
}

}  // namespace flatsos::plugin
