#pragma once
// An OpenSim muscle as a flatsos muscle (opensim_import.cpp): OpenSim's own muscle model where
// flatsos has it, with its properties as the file states them and OpenSim's defaults where it
// states none.

#include <string>
#include <vector>

#include "flatsos/muscles/muscle_parameters.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"
#include "flatsos/plugin/io/opensim_model.hpp"

namespace flatsos::plugin::opensim_import {

/// How the muscle types are read (the importer's options of the same names).
struct MuscleModelChoice {
  /// Thelen2003Muscle as OpenSim 2.x modelled it (thelen2003_opensim2, with its Vmax0 and damping
  /// where the file states none).
  bool opensim_2_muscles = false;
  /// Millard2012EquilibriumMuscle with flatsos' own laws, as any other type.
  bool millard_with_flatsos_laws = false;
  /// Every muscle as a DeGrooteFregly2016Muscle (OpenSim Moco's replaceMuscles).
  bool degroote_fregly2016_muscles = false;
  /// The DeGroote-Fregly muscles' passive fibre force left out (Moco's ignore_passive_fiber_force).
  bool ignore_passive_fiber_forces = false;
};

/// Thelen2003Muscle becomes flatsos' thelen2003 model, DeGrooteFregly2016Muscle its
/// degroote_fregly2016, and Millard2012EquilibriumMuscle a Millard2012Muscle built from the
/// file's curve properties ("<curve>/<property>" in OpenSimMuscle::properties), fiber_damping and
/// maximum_pennation_angle (OpenSim's defaults for what it leaves out); `choice` changes the first
/// and the last. Any other type keeps its common parameters with flatsos' own laws. A property
/// that flatsos models differently is named in `notes` (minimum_activation 0,
/// ignore_activation_dynamics true, compressive curves).
/// With degroote_fregly2016_muscles every muscle becomes a degroote_fregly2016 muscle as OpenSim
/// Moco's DeGrooteFregly2016Muscle::replaceMuscles maps it (ModOpReplaceMusclesWithDeGrooteFregly2016):
/// the common properties, the time constants and the tendon and passive strains of its Thelen
/// or Millard muscle (a Thelen muscle's damping 0, a Millard muscle's its own).
/// Throws OpenSimModelError naming the muscle and property for a value the model refuses, for
/// a Millard muscle with ignore_tendon_compliance true, and for a type Moco does not replace.
muscles::MuscleParameters muscle_parameters_of(const OpenSimMuscle& m, std::vector<std::string>& notes,
                                               const MuscleModelChoice& choice = {});

/// The import options' choice of muscle models.
MuscleModelChoice muscle_model_choice(const OpenSimImportOptions& options);

/// The provenance's sentence on the DeGroote-Fregly replacement.
std::string degroote_replacement(bool ignore_passive_fiber_forces);

/// The provenance's sentence on how the muscles were modelled.
std::string muscle_approximation(bool millard_with_flatsos_laws);

}  // namespace flatsos::plugin::opensim_import
