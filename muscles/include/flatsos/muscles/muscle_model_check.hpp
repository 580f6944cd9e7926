#pragma once
// A finite-difference twin for any muscle model (in the manner of Crocoddyl's NumDiff): every
// derivative a MuscleModel reports is compared with central differences of the law one order
// below, and every inverse with the law it inverts, on a grid over the muscle's working range.
// A new model's tests call it first; the planner trusts these derivatives without looking.
//
// Points where no difference can check a derivative are counted in `skipped`, not reported: a
// kink of the law (left and right one-sided differences disagree, and the reported derivative is
// one of them: the end of a tendon's toe region, activation against deactivation), and an
// inverse next to its branch point (a derivative over 20 times its scale, where two roots of the
// inverse activation dynamics merge).

#include <string>
#include <vector>

#include "flatsos/muscles/muscle_parameters.hpp"

namespace flatsos::muscles {

struct MuscleModelMismatch {
  std::string quantity;  ///< e.g. "tendonForce.slope", "excitationFromActivation round trip"
  double at = 0.0;       ///< the argument (SI) where it failed
  double reported = 0.0, expected = 0.0;
};

struct MuscleModelCheck {
  int checked = 0;  ///< comparisons made
  int skipped = 0;  ///< kinks and branch points (above)
  std::vector<MuscleModelMismatch> mismatches;
  bool ok() const { return mismatches.empty() && checked > 0; }
  /// One line per mismatch (at most 20), for a test's failure message.
  std::string summary() const;
};

/// Checks p.model's laws for the muscle p over lengths, velocities, force ratios, activations and
/// rates of its working range. `relative_tolerance` bounds |reported - expected| relative to
/// the larger of |expected| and the quantity's scale.
MuscleModelCheck check_muscle_model(const MuscleParameters& p, double relative_tolerance = 1e-6);

}  // namespace flatsos::muscles
