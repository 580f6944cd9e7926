#pragma once
// Pieces more than one muscle model uses: the Gaussian active force-length curve (Richter &
// Warner's and Thelen's are the same curve) and the error for an argument outside a law's domain.

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "flatsos/muscles/muscle_model.hpp"

namespace flatsos::muscles::detail {

/// f = exp(-((L_M - Lopt) / (W Lopt))^2), W = p.force_length_width, with its derivatives in L_M.
inline CurveJet gaussian_force_length(const MuscleParameters& p, double fiber_length_m) {
  const double width = p.force_length_width * p.optimal_fiber_length_m;
  const double x = (fiber_length_m - p.optimal_fiber_length_m) / width;
  const double f = std::exp(-x * x);
  return {f, -2.0 * x / width * f, (4.0 * x * x - 2.0) / (width * width) * f};
}

[[noreturn]] inline void domain_failure(const MuscleParameters& p, const char* what, double value) {
  std::ostringstream msg;
  msg << "muscle '" << p.name << "': " << what << " (got " << value << ")";
  throw std::domain_error(msg.str());
}

}  // namespace flatsos::muscles::detail
