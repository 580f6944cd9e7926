#pragma once
// The inverse of one muscle (docs/method/flatness.md): from its tendon force and the path's
// length, each with two time derivatives, to the fibre state, the activation and the excitation
// that produce them, and (on request) the exact gradients of activation and excitation with
// respect to (F, dF/dt, d2F/dt2) and to the path's (L, dL/dt, d2L/dt2). The flatness planner's
// inverse map and its bounded optimization (0 <= n <= 1, floor <= a <= 1 as constraints on the
// tendon-force jet, and on the joint path when it is free) share it.
//
//   L_S = Phi_S^-1(F), dL_S = dF / Phi_S', ddL_S = (ddF - Phi_S'' dL_S^2) / Phi_S'
//   x = L - L_S (the muscle along the tendon), L_M = sqrt(x^2 + h^2), cos = x / L_M (pennation
//   at constant thickness h; h = 0: L_M = x, cos = 1), u = -dL_M/dt = -cos dx/dt (shortening)
//   f = f(L_M), g = g(u), a = (F / cos - Phi_P(L_M) - D(u)) / (Fmax f g), da/dt by the chain rule
//   (D the fibre's damping; a model whose maximum velocity scales with activation has g(u / k(a))
//   there, and a is the root of that one-dimensional equation, differentiated implicitly)
//   n: the inverse of the model's activation dynamics.
// Every law is the muscle's own model's (muscle_model.hpp); the gradients are carried through
// every line in forward mode.

#include <array>

#include "flatsos/muscles/muscle_parameters.hpp"

namespace flatsos::muscles {

/// A scalar signal and its first two time derivatives (SI units of the signal per s, s^2).
struct SecondOrderJet {
  double value = 0.0, rate = 0.0, acceleration = 0.0;
};

/// d(quantity)/d(F, dF/dt, d2F/dt2).
using TendonForceJetGradient = std::array<double, 3>;
/// d(quantity)/d(L, dL/dt, d2L/dt2).
using PathLengthJetGradient = std::array<double, 3>;

struct MuscleInverse {
  enum class Stage {
    Complete,         ///< every field below is set
    SlackTendon,      ///< F <= 0: nothing past the tendon force is defined
    FiberCollapsed,   ///< pennated and x = L - L_S <= 0: the tendon is longer than the whole
                      ///< unit; only the tendon fields and fiber_length_m (= x) are set
    NoForceCapacity,  ///< g(u) <= 0 (u >= Vmax): the fibre state is set, a and n are not
  };
  Stage stage = Stage::Complete;
  double tendon_length_m = 0.0, tendon_length_rate_m_per_s = 0.0;
  double fiber_length_m = 0.0, shortening_velocity_m_per_s = 0.0;  ///< L_M and u along the fibre
  double cos_pennation = 1.0;
  double force_ratio = 0.0;  ///< g(u)
  double activation = 0.0, activation_rate_per_s = 0.0;
  double excitation = 0.0;
  bool excitation_real = true;  ///< false: no excitation gives da/dt (excitation is then the closest)
  /// Set when asked for and stage is Complete (and, for the excitation, excitation_real).
  TendonForceJetGradient activation_gradient{}, activation_rate_gradient{}, excitation_gradient{};
  /// The same with respect to the path's jet (L, dL/dt, d2L/dt2): what a joint path that moves
  /// changes through the muscle's length.
  PathLengthJetGradient path_activation_gradient{}, path_activation_rate_gradient{}, path_excitation_gradient{};
  /// How far outside the domain when stage is not Complete (>= 0, dimensionless): -F / Fmax for
  /// a slack tendon, -x / (optimal fibre length) for a collapsed fibre, -g(u) without force
  /// capacity; 0 when Complete. With its gradients (when asked for): an optimizer that starts
  /// outside the domain can move back into it.
  double domain_distance = 0.0;
  TendonForceJetGradient domain_distance_gradient{};
  PathLengthJetGradient path_domain_distance_gradient{};
};

/// Which gradients an inverse carries: none, the tendon-force jet's only (a fixed path: cheaper,
/// the same numbers), or the path-length jet's as well.
enum class InverseGradients { None, ForceJet, ForceAndPathJets };

/// `path` is the musculotendon length L and its rates (m, m/s, m/s^2).
MuscleInverse invert_muscle(const MuscleParameters& p, const SecondOrderJet& tendon_force_N,
                            const SecondOrderJet& path_length_m, InverseGradients gradients);
/// The same with every gradient (true) or none (false).
MuscleInverse invert_muscle(const MuscleParameters& p, const SecondOrderJet& tendon_force_N,
                            const SecondOrderJet& path_length_m, bool with_gradients);

}  // namespace flatsos::muscles
