#include "flatness/tied_muscles.hpp"

#include <algorithm>
#include <cmath>

#include "flatsos/plugin/model/posture_grid.hpp"

namespace flatsos::planner::detail {

namespace {
// Postures on which posture-dependent moment arms are compared: a few hundred settle whether
// two paths agree over the range (they agree everywhere when they share the points they wrap).
constexpr long kComparedPostures = 400;

// Every muscle's moment arms stacked in one column: A's, or R(q)'s over the posture grid.
Eigen::MatrixXd stacked_moment_arms(const plugin::MusculoskeletalModel& model) {
  if (model.hasConstantMomentArms()) return model.momentArmMatrix();
  const plugin::ModelDescription& d = model.description();
  std::vector<Eigen::MatrixXd> blocks;
  plugin::for_each_posture(d, plugin::posture_dependent_joints(d), kComparedPostures,
                           [&](const Eigen::VectorXd& q_rad) { blocks.push_back(model.momentArmMatrix(q_rad)); });
  const int joints = model.numJoints();
  Eigen::MatrixXd stacked(static_cast<Eigen::Index>(blocks.size()) * joints, model.numMuscles());
  for (std::size_t b = 0; b < blocks.size(); ++b) stacked.middleRows(static_cast<Eigen::Index>(b) * joints, joints) = blocks[b];
  return stacked;
}

bool agree(double a, double b, double scale, double relative_tolerance) {
  return std::abs(a - b) <= relative_tolerance * scale;
}
}  // namespace

std::vector<std::vector<int>> tied_muscle_groups(const plugin::MusculoskeletalModel& model, const Eigen::VectorXd& weights,
                                                 double relative_tolerance) {
  const Eigen::MatrixXd arms_m = stacked_moment_arms(model);
  const int m = model.numMuscles();
  std::vector<int> group_of(static_cast<std::size_t>(m), -1);
  std::vector<std::vector<int>> groups;
  for (int j = 0; j < m; ++j) {
    if (group_of[static_cast<std::size_t>(j)] >= 0) continue;
    const double arm_scale_j = arms_m.col(j).cwiseAbs().maxCoeff();
    if (arm_scale_j == 0.0) continue;  // crosses no joint: no load to share
    std::vector<int> group{j};
    for (int k = j + 1; k < m; ++k) {
      if (group_of[static_cast<std::size_t>(k)] >= 0) continue;
      const double arm_scale = std::max(arm_scale_j, arms_m.col(k).cwiseAbs().maxCoeff());
      const double weight_scale = std::max(std::abs(weights[j]), std::abs(weights[k]));
      if (!agree(weights[j], weights[k], weight_scale, relative_tolerance)) continue;
      if ((arms_m.col(j) - arms_m.col(k)).cwiseAbs().maxCoeff() <= relative_tolerance * arm_scale) group.push_back(k);
    }
    if (group.size() < 2) continue;
    for (int k : group) group_of[static_cast<std::size_t>(k)] = static_cast<int>(groups.size());
    groups.push_back(std::move(group));
  }
  return groups;
}

Eigen::VectorXd tie_broken_effort_weights(const plugin::MusculoskeletalModel& model, const Eigen::VectorXd& weights,
                                          double relative_step) {
  Eigen::VectorXd priced = weights;
  // The last muscle of a group is the cheapest: it carries the shared load, the others keep to
  // their reserves. On arm26 the other order left TRImed at its reserve with its excitation on the
  // floor along the whole hold at 60 deg, which the bounded exchange did not settle in 40 rounds.
  for (const std::vector<int>& group : tied_muscle_groups(model, weights)) {
    const auto last = static_cast<double>(group.size() - 1);
    for (std::size_t k = 0; k < group.size(); ++k) priced[group[k]] *= 1.0 + (last - static_cast<double>(k)) * relative_step;
  }
  return priced;
}

}  // namespace flatsos::planner::detail
