#pragma once
// Muscles of the paper's arm (its parameters, the remaining laws at their defaults) for the tests
// of one muscle's laws.
#include <string>

#include "flatsos/muscles/muscle_model.hpp"
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

/// A muscle of a named model with its defaults and round numbers for the rest (600 N, optimal
/// fibre 0.11 m, tendon slack 0.20 m): the muscle the model tests share.
inline muscles::MuscleParameters muscle_with_defaults(const std::string& model) {
  muscles::MuscleParameters p;
  p.name = "m";
  p.max_isometric_force_N = 600.0;
  p.optimal_fiber_length_m = 0.11;
  p.tendon_slack_length_m = 0.20;
  p.model = muscles::muscle_model_named(model);
  p.model->setDefaults(p);
  return p;
}

}  // namespace flatsos::test
