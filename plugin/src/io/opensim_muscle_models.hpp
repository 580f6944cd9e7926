#pragma once
// An OpenSim muscle as a flatsos muscle (opensim_import.cpp): OpenSim's own muscle model where
// flatsos has it, with its properties as the file states them and OpenSim's defaults where it
// states none.

#include <string>
#include <vector>

#include "flatsos/muscles/muscle_parameters.hpp"
#include "flatsos/plugin/io/opensim_model.hpp"

namespace flatsos::plugin::opensim_import {

/// Thelen2003Muscle becomes flatsos' thelen2003 model and DeGrooteFregly2016Muscle its
/// degroote_fregly2016; any other type (Millard2012EquilibriumMuscle, for now) keeps its common
/// parameters with flatsos' own laws. A property that flatsos models differently is named in
/// `notes`.
/// With opensim_2_muscles, Thelen2003Muscle becomes thelen2003_opensim2 (OpenSim 2.x's laws, its
/// Vmax0 and damping where the file states none).
/// Throws OpenSimModelError naming the muscle and property for a value the model refuses.
muscles::MuscleParameters muscle_parameters_of(const OpenSimMuscle& m, std::vector<std::string>& notes,
                                               bool opensim_2_muscles = false);

}  // namespace flatsos::plugin::opensim_import
