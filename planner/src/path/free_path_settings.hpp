#pragma once
// What the path stage works with: the user's spans and the study settings in one struct.

#include "flatsos/planner/effort.hpp"
#include "flatsos/planner/free_path.hpp"
#include "flatsos/planner/free_path_study.hpp"

namespace flatsos::planner::detail {

struct FreePathSettings : FreePathStudyOptions {
  FreePathSettings(const FreeJointPathOptions& options, const FreePathStudyOptions& study)
      : FreePathStudyOptions(study), spans(options.spans), span_growth(options.span_growth) {}
  int spans;
  double span_growth;
  /// A nonlinear effort the path stage minimizes (reduced quasi-Newton only); null: the map's
  /// linear effort.
  const Effort* effort = nullptr;
};

}  // namespace flatsos::planner::detail
