#pragma once
// The default import's ranges (import_opensim_file): OpenSim's coordinate ranges are often wider
// than a reduced model can use (a tendon that goes slack at the end of a slider's travel, a
// shoulder elevated so far that every muscle crossing it pulls the same way). The kept ranges are
// narrowed until at every posture of a grid over them each muscle's fitted length exceeds its
// tendon slack length by a tenth of its optimal fibre and each kept coordinate has muscles
// pulling both ways: each round keeps, of one coordinate, the longest run of grid layers free of
// unusable postures (the coordinate where that run is longest), and lays the grid again.

#include <array>
#include <map>
#include <string>
#include <vector>

#include "flatsos/plugin/io/opensim_model.hpp"
#include "flatsos/plugin/paths/polynomial_path_fit.hpp"

namespace flatsos::plugin::opensim_import {

using CoordinateRanges = std::map<std::string, std::array<double, 2>>;

/// The narrowed ranges (the given ones where nothing had to go). Throws OpenSimModelError when
/// no posture satisfies both conditions.
CoordinateRanges narrow_to_usable_ranges(const OpenSimModel& osim, const PathFit& fit, const CoordinateRanges& ranges);

}  // namespace flatsos::plugin::opensim_import
