#pragma once
// Rest: the tendon length at which a muscle of activation a, held at a fixed musculotendon
// length, is in static equilibrium (fiber isometric, u = 0, so g = 1):
//   Phi_S(L_S) = (max(a, floor) Fmax f(L_M) + Phi_P(L_M)) cos(phi), L_M and phi from L - L_S.
// The floor is the forward model's (effective_activation), so a simulation started there stays
// there. A pure law (no Eigen, no Simbody): usable in any file, `using namespace SimTK;` or not.

#include "flatsos/muscles/muscle_parameters.hpp"

namespace flatsos::muscles {

/// Tendon length (m) of the static equilibrium. Bracketed bisection on the tendon stretch, to
/// round-off. Throws std::domain_error naming the muscle when a is outside [0, 1] or not finite,
/// or when no equilibrium exists (the unit is not longer than the slack tendon, or the fiber
/// would need a non-positive length).
double static_equilibrium_tendon_length(const MuscleParameters& p, double musculotendon_length_m, double activation);

}  // namespace flatsos::muscles
