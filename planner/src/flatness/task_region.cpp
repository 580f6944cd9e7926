#include "flatsos/planner/task_region.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace flatsos::planner {

plugin::JointRanges task_region(const plugin::ModelDescription& model, const std::vector<Eigen::VectorXd>& postures) {
  const std::size_t n = model.joints.size();
  if (postures.empty()) throw std::invalid_argument("task region: no posture given");
  plugin::JointRanges box(n, {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()});
  for (const Eigen::VectorXd& q : postures) {
    if (static_cast<std::size_t>(q.size()) != n)
      throw std::invalid_argument("task region: a posture of " + std::to_string(q.size()) + " values for " +
                                  std::to_string(n) + " joints");
    for (std::size_t i = 0; i < n; ++i) {
      const double v = q[static_cast<Eigen::Index>(i)];
      if (!std::isfinite(v))
        throw std::invalid_argument("task region: joint '" + model.joints[i].name + "' has a non-finite value");
      box[i] = {std::min(box[i][0], v), std::max(box[i][1], v)};
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    const plugin::JointDescription& joint = model.joints[i];
    const double margin = joint.isSlider() ? kTaskRegionMargin_m : kTaskRegionMargin_rad;
    box[i] = {std::max(box[i][0] - margin, joint.range_rad[0]), std::min(box[i][1] + margin, joint.range_rad[1])};
    if (box[i][0] > box[i][1]) box[i] = {joint.range_rad[0], joint.range_rad[0]};  // the task lies beyond the range
  }
  return box;
}

FlatOutputMap flat_outputs_for_task(std::shared_ptr<const plugin::MusculoskeletalModel> model,
                                    const std::vector<Eigen::VectorXd>& postures) {
  if (!model) throw std::invalid_argument("flat outputs for a task: no model (null pointer)");
  const plugin::JointRanges region = task_region(model->description(), postures);
  try {
    return FlatOutputMap(model);
  } catch (const FlatnessError& over_ranges) {
    try {
      return FlatOutputMap::overRegion(model, region);
    } catch (const FlatnessError& over_region) {
      throw FlatnessError(std::string(over_ranges.what()) + "; nor over the task's region " +
                          plugin::describe_region(model->description(), region) + ": " + over_region.what());
    }
  }
}

}  // namespace flatsos::planner
