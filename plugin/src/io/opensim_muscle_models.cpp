#include "opensim_muscle_models.hpp"

#include <cmath>
#include <stdexcept>

#include "flatsos/muscles/degroote_fregly2016_muscle.hpp"
#include "flatsos/muscles/muscle_model.hpp"
#include "flatsos/muscles/thelen2003_muscle.hpp"
#include "flatsos/muscles/thelen2003_opensim2_muscle.hpp"
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

// Thelen (2003) as OpenSim 4's Thelen2003Muscle names its properties.
void take_thelen(const OpenSimMuscle& m, muscles::MuscleParameters& p, std::vector<std::string>& notes) {
  take(m, "FmaxTendonStrain", p.tendon_strain_at_max_force);
  take(m, "FmaxMuscleStrain", p.passive_fiber_strain_at_one_norm_force);
  double kshape_active = p.force_length_width * p.force_length_width;
  take(m, "KshapeActive", kshape_active);
  if (!(kshape_active > 0.0)) fail("muscle '" + m.name + "': KshapeActive = " + fixed(kshape_active, 4) + " must be > 0");
  p.force_length_width = std::sqrt(kshape_active);
  take(m, "KshapePassive", p.passive_force_length_shape);
  take(m, "Af", p.hill_constant);
  take(m, "Flen", p.max_eccentric_force_ratio);
  take(m, "minimum_activation", p.activation_floor);
  if (const auto t = m.properties.find("fv_linear_extrap_threshold"); t != m.properties.end() && t->second != 0.95)
    notes.push_back("muscle '" + m.name + "': fv_linear_extrap_threshold " + fixed(t->second, 3) +
                    " read as OpenSim's default 0.95 (flatsos' Thelen model fixes it)");
}

// OpenSim 2.x's Thelen reads the same curve properties as OpenSim 4's, "damping" for its fibre
// damping, and has no minimum activation.
void take_thelen_opensim2(const OpenSimMuscle& m, muscles::MuscleParameters& p) {
  take(m, "FmaxTendonStrain", p.tendon_strain_at_max_force);
  take(m, "FmaxMuscleStrain", p.passive_fiber_strain_at_one_norm_force);
  double kshape_active = p.force_length_width * p.force_length_width;
  take(m, "KshapeActive", kshape_active);
  if (!(kshape_active > 0.0)) fail("muscle '" + m.name + "': KshapeActive = " + fixed(kshape_active, 4) + " must be > 0");
  p.force_length_width = std::sqrt(kshape_active);
  take(m, "KshapePassive", p.passive_force_length_shape);
  take(m, "Af", p.hill_constant);
  take(m, "Flen", p.max_eccentric_force_ratio);
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

}  // namespace

muscles::MuscleParameters muscle_parameters_of(const OpenSimMuscle& m, std::vector<std::string>& notes,
                                               bool opensim_2_muscles) {
  muscles::MuscleParameters p;
  if (m.type == "Thelen2003Muscle" && opensim_2_muscles) {
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

}  // namespace flatsos::plugin::opensim_import
