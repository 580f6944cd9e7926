#pragma once
// Muscles of the paper's arm (its parameters, the remaining laws at their defaults) for the tests
// of one muscle's laws.
#include "flatsos/muscles/muscle_parameters.hpp"

namespace flatsos::test {

inline muscles::MuscleParameters example_triceps() {
  muscles::MuscleParameters p;
  p.name = "triceps";
  p.max_isometric_force_N = 800.0;
  p.optimal_fiber_length_m = 0.0877;
  p.tendon_slack_length_m = 0.19;
  return p;
}

}  // namespace flatsos::test
