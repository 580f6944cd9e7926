#include "opensim_muscle_models.hpp"

#include <cmath>
#include <stdexcept>

#include "flatsos/muscles/degroote_fregly2016_muscle.hpp"
#include "flatsos/muscles/millard2012_muscle.hpp"
#include "flatsos/muscles/muscle_model.hpp"
#include "flatsos/muscles/thelen2003_muscle.hpp"
#include "flatsos/muscles/thelen2003_opensim2_muscle.hpp"
#include "millard2012_fields.hpp"
#include "opensim_reduction.hpp"

namespace flatsos::plugin::opensim_import {

namespace {

// The property if the file states it.
void take(const OpenSimMuscle& m, const char* property, double& field) {
  if (const auto found = m.properties.find(property); found != m.properties.end()) field = found->second;
}

// What every OpenSim muscle states: its size, pennation, speed, time constants and floor.
void take_common(const OpenSimMuscle& m, muscles::MuscleParameters& p) {
  p.name = m.name;
  p.max_isometric_force_N = m.max_isometric_force_N;
  p.optimal_fiber_length_m = m.optimal_fiber_length_m;
  p.tendon_slack_length_m = m.tendon_slack_length_m;
  p.pennation_angle_at_optimal_rad = m.pennation_angle_at_optimal_rad;
  take(m, "max_contraction_velocity", p.max_shortening_velocity_in_optimal_lengths_per_s);
  take(m, "activation_time_constant", p.activation_time_constant_s);
  take(m, "deactivation_time_constant", p.deactivation_time_constant_s);
}

// Thelen's (2003) curve properties, named alike by OpenSim 2.x and 4.
void take_thelen_curves(const OpenSimMuscle& m, muscles::MuscleParameters& p) {
  take(m, "FmaxTendonStrain", p.tendon_strain_at_max_force);
  take(m, "FmaxMuscleStrain", p.passive_fiber_strain_at_one_norm_force);
  double kshape_active = p.force_length_width * p.force_length_width;
  take(m, "KshapeActive", kshape_active);
  if (!(kshape_active > 0.0)) fail("muscle '" + m.name + "': KshapeActive = " + fixed(kshape_active, 4) + " must be > 0");
  p.force_length_width = std::sqrt(kshape_active);
  take(m, "KshapePassive", p.passive_force_length_shape);
  take(m, "Af", p.hill_constant);
  take(m, "Flen", p.max_eccentric_force_ratio);
}

// Thelen (2003) as OpenSim 4's Thelen2003Muscle names its properties.
void take_thelen(const OpenSimMuscle& m, muscles::MuscleParameters& p, std::vector<std::string>& notes) {
  take_thelen_curves(m, p);
  take(m, "minimum_activation", p.activation_floor);
  if (const auto t = m.properties.find("fv_linear_extrap_threshold"); t != m.properties.end() && t->second != 0.95)
    notes.push_back("muscle '" + m.name + "': fv_linear_extrap_threshold " + fixed(t->second, 3) +
                    " read as OpenSim's default 0.95 (flatsos' Thelen model fixes it)");
}

// OpenSim 2.x's Thelen reads the same curve properties as OpenSim 4's, "damping" for its fibre
// damping, and has no minimum activation.
void take_thelen_opensim2(const OpenSimMuscle& m, muscles::MuscleParameters& p) {
  take_thelen_curves(m, p);
  take(m, "damping", p.fiber_damping);
  take(m, "Vmax", p.max_shortening_velocity_in_optimal_lengths_per_s);
  if (const auto v0 = m.properties.find("Vmax0");
      v0 != m.properties.end() && v0->second != muscles::Thelen2003OpenSim2Muscle::kMaxVelocityAtRestInOptimalLengthsPerS)
    fail("muscle '" + m.name + "': Vmax0 = " + fixed(v0->second, 4) + " (flatsos' OpenSim 2.x Thelen model fixes it at 5)");
}

void take_degroote(const OpenSimMuscle& m, muscles::MuscleParameters& p) {
  take(m, "tendon_strain_at_one_norm_force", p.tendon_strain_at_max_force);
  take(m, "active_force_width_scale", p.force_length_width);
  take(m, "passive_fiber_strain_at_one_norm_force", p.passive_fiber_strain_at_one_norm_force);
  if (const auto off = m.properties.find("ignore_passive_fiber_force"); off != m.properties.end() && off->second != 0.0)
    p.passive_fiber_strain_at_one_norm_force = 0.0;
  take(m, "activation_dynamics_smoothing", p.activation_dynamics_smoothing);
  take(m, "fiber_damping", p.fiber_damping);
}

bool stated_true(const OpenSimMuscle& m, const char* property) {
  const auto found = m.properties.find(property);
  return found != m.properties.end() && found->second != 0.0;
}

// The curve properties the file states; OpenSim's defaults for the rest.
muscles::Millard2012CurveParameters millard_curves(const OpenSimMuscle& m, std::vector<std::string>& notes) {
  muscles::Millard2012CurveParameters curves;
  bool compressive_stated = false;
  millard2012_fields::for_each_property(curves, [&](const char* curve, const char*, const char* property, auto& field) {
    const auto found = m.properties.find(std::string(curve) + "/" + property);
    if (found == m.properties.end()) return;
    if (millard2012_fields::equilibrium_muscle_curve(curve)) field = found->second;
    else compressive_stated = true;
  });
  if (compressive_stated)
    notes.push_back("muscle '" + m.name + "': its compressive curves are not read (a Millard2012EquilibriumMuscle has none; "
                    "OpenSim ignores them too)");
  return curves;
}

// Millard2012EquilibriumMuscle as OpenSim builds it: its curves from the file's curve properties,
// adjusted to its damping, with its maximum pennation; OpenSim's defaults where the file is silent.
void take_millard(const OpenSimMuscle& m, muscles::MuscleParameters& p, std::vector<std::string>& notes) {
  if (stated_true(m, "ignore_tendon_compliance"))
    fail("muscle '" + m.name + "': ignore_tendon_compliance = true is not supported (flatsos' Millard muscle has an "
         "elastic tendon; a rigid one would change every force)");
  muscles::Millard2012MuscleConfiguration configuration;
  take(m, "fiber_damping", configuration.fiber_damping);
  double maximum_pennation_rad = muscles::Millard2012Muscle::defaultMaximumPennationAngle();
  take(m, "maximum_pennation_angle", maximum_pennation_rad);
  try {
    p.model = std::make_shared<const muscles::Millard2012Muscle>(millard_curves(m, notes), configuration, maximum_pennation_rad);
  } catch (const std::invalid_argument& e) {
    fail("muscle '" + m.name + "': " + e.what() + " (read from the OpenSim file)");
  }
  p.model->setDefaults(p);
  take_common(m, p);
  take(m, "minimum_activation", p.activation_floor);
  if (p.activation_floor < 0.0)
    fail("muscle '" + m.name + "': minimum_activation = " + fixed(p.activation_floor, 4) + " must be >= 0 (as OpenSim requires)");
  if (p.activation_floor == 0.0) {
    p.activation_floor = muscles::MuscleParameters().activation_floor;
    notes.push_back("muscle '" + m.name + "': minimum_activation 0 read as " + fixed(p.activation_floor, 4) +
                    " (flatsos' activation floor must be > 0): its activation stays at or above that");
  }
  if (stated_true(m, "ignore_activation_dynamics"))
    notes.push_back("muscle '" + m.name + "': ignore_activation_dynamics = true read as false: flatsos' muscles have "
                    "activation dynamics; a plan's activation is what OpenSim would take as this muscle's excitation");
}

// Another type: the common parameters and the strains OpenSim's reader found, with flatsos'
// default laws (Richter & Warner's).
void take_other(const OpenSimMuscle& m, muscles::MuscleParameters& p) {
  // OpenSim's minimum activation is flatsos' activation floor: the same clamp from below, and the
  // bound every plan keeps.
  p.activation_floor = m.minimum_activation;
  p.tendon_strain_at_max_force = m.tendon_strain_at_one_norm_force;
  p.passive_fiber_strain_at_one_norm_force = m.passive_fiber_strain_at_one_norm_force;
  p.activation_time_constant_s = m.activation_time_constant_s;
  p.deactivation_time_constant_s = m.deactivation_time_constant_s;
  p.max_shortening_velocity_in_optimal_lengths_per_s = m.max_contraction_velocity_in_optimal_lengths_per_s;
}

// OpenSim Moco's DeGrooteFregly2016Muscle::replaceMuscles: the common properties and time
// constants; from a Thelen muscle its FmaxTendonStrain and FmaxMuscleStrain (Thelen's defaults
// where the file is silent) and no damping; from a Millard muscle its curves' strains and its
// fiber_damping; a DeGrooteFregly2016Muscle as it is.
void take_as_degroote(const OpenSimMuscle& m, muscles::MuscleParameters& p) {
  p.model = muscles::muscle_model_named(muscles::DeGrooteFregly2016Muscle::kName);
  p.model->setDefaults(p);
  take_common(m, p);
  if (m.type == "Thelen2003Muscle") {
    muscles::MuscleParameters thelen;
    thelen.model = muscles::muscle_model_named(muscles::Thelen2003Muscle::kName);
    thelen.model->setDefaults(thelen);
    take_thelen_curves(m, thelen);
    p.tendon_strain_at_max_force = thelen.tendon_strain_at_max_force;
    p.passive_fiber_strain_at_one_norm_force = thelen.passive_fiber_strain_at_one_norm_force;
    p.fiber_damping = 0.0;
  } else if (m.type == "Millard2012EquilibriumMuscle") {
    p.tendon_strain_at_max_force = m.tendon_strain_at_one_norm_force;
    p.passive_fiber_strain_at_one_norm_force = m.passive_fiber_strain_at_one_norm_force;
    p.fiber_damping = muscles::Millard2012MuscleConfiguration().fiber_damping;
    take(m, "fiber_damping", p.fiber_damping);
  } else if (m.type == "DeGrooteFregly2016Muscle") {
    take_degroote(m, p);
  } else {
    fail("muscle '" + m.name + "' is a " + m.type +
         ", which OpenSim Moco does not replace by a DeGrooteFregly2016Muscle (it replaces Thelen2003Muscle and "
         "Millard2012EquilibriumMuscle)");
  }
}

}  // namespace

muscles::MuscleParameters muscle_parameters_of(const OpenSimMuscle& m, std::vector<std::string>& notes,
                                               const MuscleModelChoice& choice) {
  if (choice.opensim_2_muscles && choice.degroote_fregly2016_muscles)
    fail("opensim_2_muscles and degroote_fregly2016_muscles exclude each other");
  if (choice.ignore_passive_fiber_forces && !choice.degroote_fregly2016_muscles)
    fail("ignore_passive_fiber_forces applies to DeGroote-Fregly muscles: ask for degroote_fregly2016_muscles too");
  muscles::MuscleParameters p;
  if (choice.degroote_fregly2016_muscles) {
    take_as_degroote(m, p);
    if (choice.ignore_passive_fiber_forces) p.passive_fiber_strain_at_one_norm_force = 0.0;
  } else if (m.type == "Thelen2003Muscle" && choice.opensim_2_muscles) {
    p.model = muscles::muscle_model_named(muscles::Thelen2003OpenSim2Muscle::kName);
    p.model->setDefaults(p);
    take_common(m, p);
    take_thelen_opensim2(m, p);
  } else if (m.type == "Thelen2003Muscle") {
    p.model = muscles::muscle_model_named(muscles::Thelen2003Muscle::kName);
    p.model->setDefaults(p);
    take_common(m, p);
    take_thelen(m, p, notes);
  } else if (m.type == "DeGrooteFregly2016Muscle") {
    p.model = muscles::muscle_model_named(muscles::DeGrooteFregly2016Muscle::kName);
    p.model->setDefaults(p);
    take_common(m, p);
    take_degroote(m, p);
  } else if (m.type == "Millard2012EquilibriumMuscle" && !choice.millard_with_flatsos_laws) {
    take_millard(m, p, notes);
  } else {
    take_common(m, p);
    take_other(m, p);
  }
  try {
    muscles::validate(p);
  } catch (const std::invalid_argument& e) {
    fail(std::string(e.what()) + " (read from the OpenSim file)");
  }
  return p;
}

MuscleModelChoice muscle_model_choice(const OpenSimImportOptions& options) {
  return {options.opensim_2_muscles, options.millard_with_flatsos_laws, options.degroote_fregly2016_muscles,
          options.ignore_passive_fiber_forces};
}

std::string degroote_replacement(bool ignore_passive_fiber_forces) {
  return std::string("every muscle replaced by a DeGrooteFregly2016Muscle as OpenSim Moco's replaceMuscles maps it") +
         (ignore_passive_fiber_forces ? ", its passive fibre force ignored" : "");
}

std::string muscle_approximation(bool millard_with_flatsos_laws) {
  if (millard_with_flatsos_laws)
    return "muscles: Thelen2003Muscle and DeGrooteFregly2016Muscle as OpenSim models them, with the file's properties; "
           "other types (Millard2012EquilibriumMuscle) with OpenSim's maximum isometric force, optimal fibre length, "
           "tendon slack length, pennation, maximum contraction velocity and curve strains and flatsos' Hill laws in place "
           "of their curves";
  return "muscles: Thelen2003Muscle, DeGrooteFregly2016Muscle and Millard2012EquilibriumMuscle (its curves from the "
         "file's curve properties, its fiber damping and maximum pennation) as OpenSim models them, with the file's "
         "properties and OpenSim's defaults for the rest; other types with OpenSim's common properties and flatsos' Hill "
         "laws";
}

}  // namespace flatsos::plugin::opensim_import
