#pragma once
// The kinematics of an OpenSim 3 model file (format version < 30505: each joint inside its
// child <Body>, with location_in_parent / orientation_in_parent and location / orientation),
// read into flatsos' OpenSimModel so that opensim_body_in_ground and GeometryPathEvaluator work
// on it: bodies (mass properties when given), joints (OpenSim 4's offset frames: F in the
// parent, M in the child), coordinates, coordinate couplers. Muscles are not read (their paths
// are: read_opensim_geometry_paths reads both formats). OpenSim 4 files: read_opensim_model.

#include <string>

#include "flatsos/plugin/io/opensim_model.hpp"

namespace flatsos::plugin {

/// Throws OpenSimFileError naming the file, the body or joint and the field for: a document
/// without a Model, a joint without a parent body or with <reverse>true</reverse>, a number
/// that does not parse, an axis of length 0, a coordinate given twice.
OpenSimModel parse_opensim3_model(const std::string& xml, const std::string& source);
OpenSimModel read_opensim3_model(const std::string& file);

}  // namespace flatsos::plugin
