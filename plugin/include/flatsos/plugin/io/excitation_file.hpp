#pragma once
// Excitation schedules from CSV (a header "time,<muscle>,<muscle>,...", then rows of numbers)
// or from a controls .sto as OpenSim Moco writes it (columns "time", "/forceset/<muscle>", ...;
// plain "<muscle>" is accepted too). Any column order, one column per muscle of the model, times
// strictly increasing, excitations in [0, 1]. Each muscle gets a PiecewiseLinearSignal (held
// after the last row).

#include <memory>
#include <string>
#include <vector>

#include "flatsos/plugin/force/excitation_signal.hpp"

namespace flatsos::plugin {

/// Signals in the order of `muscle_names`. Throws std::runtime_error naming the file, line or
/// column: missing or unknown muscle columns, non-numbers, NaN, excitations outside [0, 1],
/// times not increasing, no rows.
std::vector<std::shared_ptr<const ExcitationSignal>> read_excitation_csv(
    const std::string& path, const std::vector<std::string>& muscle_names);
/// The same from a controls .sto (the same errors, naming the file and the row or column).
std::vector<std::shared_ptr<const ExcitationSignal>> read_excitation_sto(
    const std::string& path, const std::vector<std::string>& muscle_names);
/// read_excitation_sto for a path ending in ".sto", read_excitation_csv otherwise.
std::vector<std::shared_ptr<const ExcitationSignal>> read_excitation_file(
    const std::string& path, const std::vector<std::string>& muscle_names);

}  // namespace flatsos::plugin
