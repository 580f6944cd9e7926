#pragma once
// The checks validate() and each muscle model's validate() share: a message that names the
// muscle, the field, its value and what it must be.

#include "flatsos/muscles/muscle_parameters.hpp"

namespace flatsos::muscles {

[[noreturn]] void reject(const MuscleParameters& p, const char* field, double value, const char* requirement);
void require_positive(const MuscleParameters& p, const char* field, double value);

}  // namespace flatsos::muscles
