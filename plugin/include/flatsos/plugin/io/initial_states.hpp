#pragma once
// A model's initial state from a states file (.sto), as OpenSim's forward tool takes it: the
// first row. Columns are found by OpenSim 3 names ("r_elbow_flex", "r_elbow_flex_u",
// "TRIlong.activation", "TRIlong.fiber_length") or OpenSim 4 paths
// ("/jointset/<joint>/<coordinate>/value", ".../speed", "/forceset/<muscle>/activation",
// ".../fiber_length"); flatsos' own states files also give ".../tendon_length". A fibre length
// becomes the tendon length L - sqrt(L_M^2 - h^2) at the row's posture (h the fibre's constant
// thickness). What the file does not give is left as the state has it, except a muscle with
// neither fibre nor tendon length: its tendon starts in static equilibrium at its activation.

#include <string>
#include <vector>

#include <Simbody.h>

#include "flatsos/plugin/io/sto_file.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace flatsos::plugin {

/// Sets s from the table's first row; returns one line per thing taken from elsewhere (a
/// coordinate, speed or muscle state the file lacks). Angles in degrees when the table says
/// so (inDegrees=yes). Throws std::invalid_argument naming the file and the column for a
/// table without rows, a value that is not finite, an activation outside [0, 1] or a fibre
/// shorter than its thickness.
std::vector<std::string> set_initial_states(const MusculoskeletalModel& model, SimTK::State& s, const StoTable& table,
                                            const std::string& source);

}  // namespace flatsos::plugin
