#pragma once
// The model file's muscle fields that its reader (model_file.cpp) and its writer
// (model_file_writer.cpp) share: one table, so the two cannot drift apart.

#include "flatsos/muscles/muscle_parameters.hpp"

#include <string>

namespace flatsos::plugin::model_file {

// An element of a list as error messages name it: indexed("muscles", 2) is "muscles[2]".
inline std::string indexed(const std::string& list, std::size_t i) { return list + "[" + std::to_string(i) + "]"; }

// The optional MuscleParameters fields, by their JSON names (read and written alike).
struct OptionalMuscleField {
  const char* key;
  double muscles::MuscleParameters::*member;
};
inline constexpr OptionalMuscleField kOptionalMuscleFields[] = {
    {"tendon_strain_at_max_force", &muscles::MuscleParameters::tendon_strain_at_max_force},
    {"force_length_width", &muscles::MuscleParameters::force_length_width},
    {"max_shortening_velocity_in_optimal_lengths_per_s",
     &muscles::MuscleParameters::max_shortening_velocity_in_optimal_lengths_per_s},
    {"hill_constant", &muscles::MuscleParameters::hill_constant},
    {"max_eccentric_force_ratio", &muscles::MuscleParameters::max_eccentric_force_ratio},
    {"activation_time_constant_s", &muscles::MuscleParameters::activation_time_constant_s},
    {"deactivation_time_constant_s", &muscles::MuscleParameters::deactivation_time_constant_s},
    {"activation_floor", &muscles::MuscleParameters::activation_floor},
    {"pennation_angle_at_optimal_rad", &muscles::MuscleParameters::pennation_angle_at_optimal_rad},
    {"passive_fiber_strain_at_one_norm_force", &muscles::MuscleParameters::passive_fiber_strain_at_one_norm_force},
    {"passive_force_length_shape", &muscles::MuscleParameters::passive_force_length_shape},
    {"activation_dynamics_smoothing", &muscles::MuscleParameters::activation_dynamics_smoothing},
    {"fiber_damping", &muscles::MuscleParameters::fiber_damping},
};

// "muscle_model": the laws the muscle follows, by name (muscle_model.hpp).
inline constexpr const char* kMuscleModelKey = "muscle_model";

}  // namespace flatsos::plugin::model_file
