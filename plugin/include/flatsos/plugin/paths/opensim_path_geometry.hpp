#pragma once
// OpenSim GeometryPaths behind the simulation's path seam (model/path_geometry.hpp): a muscle of
// an imported model simulated with its via points and wrapping, as OpenSim evaluates them
// (path_evaluation.hpp), the coordinates the import held at their values and coupled ones
// following their independent coordinate.

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "flatsos/plugin/io/opensim_model.hpp"
#include "flatsos/plugin/model/model_description.hpp"
#include "flatsos/plugin/paths/geometry_path.hpp"

namespace flatsos::plugin {

/// Sets every muscle's path_geometry of `model` (imported from `osim`, whose joints carry the
/// OpenSim coordinate names) to its GeometryPath. `held`: the values the import held the other
/// coordinates at (absent: 0). Throws OpenSimModelError naming the muscle for a muscle without
/// a GeometryPath or one flatsos cannot evaluate.
void attach_geometry_paths(ModelDescription& model, std::shared_ptr<const OpenSimModel> osim,
                           std::shared_ptr<const OpenSimGeometryPaths> geometry, const std::map<std::string, double>& held);

}  // namespace flatsos::plugin
