#pragma once
// Initial states at rest: the tendon length at which a muscle of activation a, held at a fixed
// musculotendon length, is in static equilibrium (fiber isometric, u = 0, so g = 1):
//   Phi_S(L_S) = max(a, floor) Fmax f(L - L_S).
// The floor is the forward model's (muscles::effective_activation), so a simulation started
// there stays there.

#include <Eigen/Core>
#include <Simbody.h>

#include "flatsos/muscles/muscle_parameters.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace flatsos::plugin {

/// Tendon length (m) of the static equilibrium. Bracketed bisection on the tendon stretch, to
/// round-off. Throws std::domain_error naming the muscle when a is outside [0, 1] or not finite,
/// or when no equilibrium exists (the unit is not longer than the slack tendon, or the fiber
/// would need a non-positive length).
double static_equilibrium_tendon_length(const muscles::MuscleParameters& p,
                                        double musculotendon_length_m, double activation);

/// Sets every muscle's tendon length to its static equilibrium for the given activations at the
/// state's joint angles, and the activations themselves.
void equilibrate_tendons(const MusculoskeletalModel& model, SimTK::State& s,
                         const Eigen::VectorXd& activations);

}  // namespace flatsos::plugin
