#pragma once
// OpenSim-style tables of a simulation (one row per report time): the states, as OpenSim's
// states files name them (/jointset/<joint>/<coordinate>/value and /speed, radians), and the
// controls apart, as Moco's controls files do (/forceset/<muscle>: the excitation).

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there

#include <string>

#include <Simbody.h>

#include "flatsos/plugin/io/sto_file.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace flatsos::plugin {

/// "/jointset/<joint>/<coordinate>/value" and ".../speed" of joint i.
std::string coordinate_value_column(const MusculoskeletalModel& model, int joint);
std::string coordinate_speed_column(const MusculoskeletalModel& model, int joint);

/// An empty state table with columns time, then per joint its coordinate's value and speed
/// (rad, rad/s), then per muscle /forceset/<muscle>/{activation, tendon_length, tendon_force,
/// fiber_length, fiber_velocity} (SI; fiber_velocity is the lengthening rate).
StoTable make_state_table(const MusculoskeletalModel& model, const std::string& name = "states");
/// Appends one row for `s` (realized here to Stage::Velocity).
void append_state_row(const MusculoskeletalModel& model, const SimTK::State& s, StoTable& table);

/// An empty controls table: time, then /forceset/<muscle> per muscle (the excitation).
StoTable make_controls_table(const MusculoskeletalModel& model, const std::string& name = "controls");
/// Appends the excitations the muscles receive at `s` (clamped to [0, 1], as applied).
void append_controls_row(const MusculoskeletalModel& model, const SimTK::State& s, StoTable& table);

}  // namespace flatsos::plugin
