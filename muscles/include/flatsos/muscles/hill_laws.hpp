#pragma once
// A Hill-type muscle's laws for any muscle model: each function below evaluates the law of the
// muscle's own model (MuscleParameters::model, muscle_model.hpp). Both the Simbody force element
// (forward dynamics) and the planner (inverse map) call these, so planned and simulated
// trajectories share one set of laws. SI units: lengths m, velocities m/s, forces N, time s.
//
// Sign conventions: u is the fiber *shortening* velocity (u > 0 concentric), z the force ratio
// (active fibre force) / (a Fmax f(L_M)); g(u) = z is the force-velocity law.

#include "flatsos/muscles/muscle_model.hpp"
#include "flatsos/muscles/muscle_parameters.hpp"

namespace flatsos::muscles {

// ---- Tendon: 0 at and below slack.
inline double tendon_force(const MuscleParameters& p, double tendon_length_m) {
  return p.model->tendonForce(p, tendon_length_m).value;
}
inline double tendon_force_derivative(const MuscleParameters& p, double tendon_length_m) {  ///< N/m
  return p.model->tendonForce(p, tendon_length_m).slope;
}
inline double tendon_force_second_derivative(const MuscleParameters& p, double tendon_length_m) {  ///< N/m^2
  return p.model->tendonForce(p, tendon_length_m).curvature;
}
/// Inverse of the tendon law on its strictly increasing branch. Throws std::domain_error for
/// F <= 0 or non-finite F (a slack tendon has no unique length).
inline double tendon_length_from_force(const MuscleParameters& p, double tendon_force_N) {
  return p.model->tendonLengthFromForce(p, tendon_force_N);
}

// ---- Active force-length f(L_M), in (0, 1], L_M the fibre length.
inline double force_length(const MuscleParameters& p, double fiber_length_m) {
  return p.model->activeForceLength(p, fiber_length_m).value;
}
inline double force_length_derivative(const MuscleParameters& p, double fiber_length_m) {  ///< 1/m
  return p.model->activeForceLength(p, fiber_length_m).slope;
}
inline double force_length_second_derivative(const MuscleParameters& p, double fiber_length_m) {  ///< 1/m^2
  return p.model->activeForceLength(p, fiber_length_m).curvature;
}

// ---- Force-velocity g(u): g(0) = 1, decreasing.
inline double force_velocity(const MuscleParameters& p, double shortening_velocity_m_per_s) {
  return p.model->forceVelocity(p, shortening_velocity_m_per_s).value;
}
inline double force_velocity_derivative(const MuscleParameters& p, double shortening_velocity_m_per_s) {
  return p.model->forceVelocity(p, shortening_velocity_m_per_s).slope;
}
/// Each branch's own second derivative where g is only C1.
inline double force_velocity_second_derivative(const MuscleParameters& p, double shortening_velocity_m_per_s) {
  return p.model->forceVelocity(p, shortening_velocity_m_per_s).curvature;
}
/// Exact inverse of g on its range. Throws std::domain_error outside it.
inline double force_velocity_inverse(const MuscleParameters& p, double force_ratio) {
  return p.model->forceVelocityInverse(p, force_ratio);
}
/// Upper end of the force ratios where the forward model uses the exact inverse of g.
inline double force_ratio_exact_upper_bound(const MuscleParameters& p) {
  return p.model->forceRatioExactUpperBound(p);
}
/// The inverse of g used by the forward model: exact on [0, z_hi], continued so that it is C1,
/// strictly decreasing and finite for every finite z.
inline double fiber_velocity_from_force_ratio(const MuscleParameters& p, double force_ratio) {
  return p.model->fiberVelocityFromForceRatio(p, force_ratio).value;
}
inline double fiber_velocity_from_force_ratio_derivative(const MuscleParameters& p, double force_ratio) {
  return p.model->fiberVelocityFromForceRatio(p, force_ratio).slope;
}

// ---- Passive fibre force Phi_P(L_M), N: 0 for every length when the muscle has none.
inline double passive_fiber_force(const MuscleParameters& p, double fiber_length_m) {
  return p.model->passiveFiberForce(p, fiber_length_m).value;
}
inline double passive_fiber_force_derivative(const MuscleParameters& p, double fiber_length_m) {  ///< N/m
  return p.model->passiveFiberForce(p, fiber_length_m).slope;
}
inline double passive_fiber_force_second_derivative(const MuscleParameters& p, double fiber_length_m) {  ///< N/m^2
  return p.model->passiveFiberForce(p, fiber_length_m).curvature;
}

// ---- Pennation at constant fibre thickness h = Lopt sin(phi0) (p.fiber_thickness_m()).
/// The fibre from the muscle's length along the tendon x = L - L_S: L_M = sqrt(x^2 + h^2),
/// cos(phi) = x / L_M, with dL_M/dx = cos(phi) and d cos(phi)/dx = h^2 / L_M^3. Without
/// pennation (h = 0) exactly L_M = x and cos(phi) = 1.
struct FiberGeometry {
  double length_m = 0.0;             ///< L_M
  double cos_pennation = 1.0;        ///< x / L_M
  double length_d_along = 1.0;       ///< dL_M/dx
  double cos_pennation_d_along = 0.0;  ///< d cos(phi)/dx, 1/m
};
FiberGeometry fiber_geometry(const MuscleParameters& p, double along_tendon_m);

// ---- Contraction dynamics. ----
// The tendon carries the fibre's force projected on its line:
//   Phi_S(L_S) = (a Fmax f(L_M) g(u / k(a)) + Phi_P(L_M) + D(u)) cos(phi),
// with L_M, phi from x = L - L_S (fiber_geometry), u the fibre's shortening velocity along
// itself (so x shortens at u / cos(phi)), k(a) the model's maximum-velocity scale (1 for most)
// and D(u) = -fiber_damping Fmax u / Vmax the fibre's damping.

/// The activation the contraction dynamics use: max(a, activation_floor).
double effective_activation(const MuscleParameters& p, double activation);

/// The force ratio z = g(u / k) of the force balance at the muscle length along the tendon
/// x = L - L_S: without damping (F_S / cos(phi) - Phi_P(L_M)) / (max(a, floor) Fmax f(L_M)),
/// with damping the root of the balance (one, found by a safeguarded Newton iteration). Finite
/// for every finite input: f is floored at 1e-12 (an absurd fibre length underflows exp),
/// cos(phi) at 1e-2 (a fibre squeezed to its thickness).
double force_ratio(const MuscleParameters& p, double tendon_force_N, double activation,
                   double along_tendon_m);

/// Fibre shortening velocity u = k(a) g^-1(z) along the fibre, of the forward model (safe
/// extension included); 0 while the fibre is held at the model's minimum length
/// (MuscleModel::minimumFiberLength: below it, or at it with u >= 0).
double fiber_shortening_velocity(const MuscleParameters& p, double tendon_force_N,
                                 double activation, double along_tendon_m);

/// Time derivative of the tendon length: dL_S/dt = u / cos(phi) + dL/dt, where dL/dt is the
/// muscle-tendon unit's lengthening rate (-r(q)^T qd).
double tendon_length_derivative(const MuscleParameters& p, double tendon_length_m,
                                double activation, double musculotendon_length_m,
                                double musculotendon_lengthening_rate_m_per_s);

/// Partial derivatives of dL_S/dt (tendon_length_derivative): the stiff part of the muscle's ODE
/// (own states) and how the path drives it, used by the linearly implicit integrator. The
/// partial with respect to the path's lengthening rate is 1. Below the activation floor the
/// activation partial is 0.
struct TendonLengthDerivativePartials {
  double d_tendon_length_per_s = 0.0;        ///< d(dL_S/dt)/dL_S, 1/s (large and negative at low a)
  double d_activation_m_per_s = 0.0;         ///< d(dL_S/dt)/da, m/s
  double d_musculotendon_length_per_s = 0.0; ///< d(dL_S/dt)/dL, 1/s
};
TendonLengthDerivativePartials tendon_length_derivative_partials(const MuscleParameters& p,
                                                                 double tendon_length_m,
                                                                 double activation,
                                                                 double musculotendon_length_m);

// ---- Activation dynamics da/dt = rate(n, a) of the muscle's model.
inline double activation_derivative(const MuscleParameters& p, double excitation, double activation) {
  return p.model->activationRate(p, excitation, activation).value;
}
inline double activation_derivative_d_excitation(const MuscleParameters& p, double excitation,
                                                 double activation) {
  return p.model->activationRate(p, excitation, activation).d_excitation;
}
inline double activation_derivative_d_activation(const MuscleParameters& p, double excitation,
                                                 double activation) {
  return p.model->activationRate(p, excitation, activation).d_activation;
}

/// Excitation n with rate(n, a) = da/dt (ExcitationFromActivation says when there is none).
inline ExcitationFromActivation excitation_from_activation(const MuscleParameters& p, double activation,
                                                           double activation_rate_per_s) {
  return p.model->excitationFromActivation(p, activation, activation_rate_per_s);
}

/// The excitation bounds 0 <= n <= 1 as smooth conditions on (a, da/dt) (muscle_model.hpp).
inline ExcitationBoundMargins excitation_bound_margins(const MuscleParameters& p, double activation,
                                                       double activation_rate_per_s) {
  return p.model->excitationBoundMargins(p, activation, activation_rate_per_s);
}

}  // namespace flatsos::muscles
