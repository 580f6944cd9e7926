#pragma once
// The OpenSim-style table of a simulation's states (one row per report time).

#include <string>

#include <Simbody.h>

#include "flatsos/plugin/io/sto_file.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace flatsos::plugin {

/// An empty state table with columns time, /jointset/<joint>/q, /jointset/<joint>/qdot (rad,
/// rad/s), and per muscle /forceset/<muscle>/{excitation, activation, tendon_length,
/// tendon_force, fiber_length, fiber_velocity} (SI; fiber_velocity is the lengthening rate).
StoTable make_state_table(const MusculoskeletalModel& model, const std::string& name = "states");
/// Appends one row for `s` (realized here to Stage::Velocity).
void append_state_row(const MusculoskeletalModel& model, const SimTK::State& s, StoTable& table);

}  // namespace flatsos::plugin
