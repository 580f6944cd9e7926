#pragma once
// The Hill muscle laws (docs/method/flatness.md, the model) as pure functions. Both the Simbody force
// element (forward dynamics) and the planner (inverse map) call these, so planned and simulated
// trajectories share one set of laws. SI units: lengths m, velocities m/s, forces N, time s.
//
// Sign conventions: u is the fiber *shortening* velocity (u > 0 concentric), z the force ratio
// (active fibre force) / (a Fmax f(L_M)); g(u) = z is the force-velocity law.

#include "flatsos/muscles/muscle_parameters.hpp"

namespace flatsos::muscles {

// ---- Tendon: Phi_S(L_S) = k (L_S - L_slack)^2 above slack, 0 below (C1 at slack). ----
double tendon_force(const MuscleParameters& p, double tendon_length_m);
double tendon_force_derivative(const MuscleParameters& p, double tendon_length_m);         ///< N/m
double tendon_force_second_derivative(const MuscleParameters& p, double tendon_length_m);  ///< N/m^2
/// Inverse of the tendon law on its strictly increasing branch: L_slack + sqrt(F / k).
/// Throws std::domain_error for F <= 0 or non-finite F (a slack tendon has no unique length).
double tendon_length_from_force(const MuscleParameters& p, double tendon_force_N);

// ---- Force-length: f(L_M) = exp(-((L_M - Lopt) / (W Lopt))^2), in (0, 1], L_M the fibre length. ----
double force_length(const MuscleParameters& p, double fiber_length_m);
double force_length_derivative(const MuscleParameters& p, double fiber_length_m);  ///< 1/m
double force_length_second_derivative(const MuscleParameters& p, double fiber_length_m);  ///< 1/m^2

// ---- Force-velocity g(u): g(0) = 1, g(Vmax) = 0, g -> gmax for u -> -inf. ----
double force_velocity(const MuscleParameters& p, double shortening_velocity_m_per_s);
double force_velocity_derivative(const MuscleParameters& p, double shortening_velocity_m_per_s);
/// Each branch's own second derivative (g'' jumps at u = 0, where g is C1).
double force_velocity_second_derivative(const MuscleParameters& p, double shortening_velocity_m_per_s);

/// Exact inverse of g on its range: valid for force ratios z in (0, gmax) (also for z in
/// (-Ah, 0], where it returns u > Vmax). Throws std::domain_error outside (-Ah, gmax).
double force_velocity_inverse(const MuscleParameters& p, double force_ratio);

/// Upper end of the force ratios where the forward model uses the exact inverse of g:
/// z_hi = 1 + 0.9 (gmax - 1). Above it the inverse has a pole at gmax.
double force_ratio_exact_upper_bound(const MuscleParameters& p);

/// The inverse of g used by the forward model: exactly force_velocity_inverse on
/// [0, z_hi], continued linearly (value and slope match, so it is C1 and strictly decreasing)
/// for z < 0 (the fiber pushes: only with a parallel element or round-off) and for z > z_hi
/// (the pole at gmax would send u to -inf). Finite for every finite z.
double fiber_velocity_from_force_ratio(const MuscleParameters& p, double force_ratio);
double fiber_velocity_from_force_ratio_derivative(const MuscleParameters& p, double force_ratio);

// ---- Passive fibre force (only when p.hasPassiveFiberForce()): with y = kPE (L_M/Lopt - 1)/e0,
// kPE = 4 and e0 = passive_fiber_strain_at_one_norm_force,
//   Phi_P(L_M) = Fmax (e^y - 1 - y - y^2/2) / (e^kPE - 1 - kPE - kPE^2/2) for y > 0, 0 below:
// Fmax at strain e0 and Thelen's (2003) exponential growth, but C2 at the optimal length (value,
// slope and curvature 0 there) where Thelen's curve has a kink: the planner's inverse map takes
// its second derivative. 0 for every length when the passive force is off.
double passive_fiber_force(const MuscleParameters& p, double fiber_length_m);
double passive_fiber_force_derivative(const MuscleParameters& p, double fiber_length_m);         ///< N/m
double passive_fiber_force_second_derivative(const MuscleParameters& p, double fiber_length_m);  ///< N/m^2

// ---- Pennation at constant fibre thickness h = Lopt sin(phi0) (p.fiber_thickness_m()). ----
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
//   Phi_S(L_S) = (a Fmax f(L_M) g(u) + Phi_P(L_M)) cos(phi),
// with L_M, phi from x = L - L_S (fiber_geometry) and u the fibre's shortening velocity along
// itself, so x shortens at u / cos(phi). Without pennation and passive force this is the
// paper's Phi_S = a Fmax f(L_C) g(u), L_C = x.

/// The activation the contraction dynamics use: max(a, activation_floor).
double effective_activation(const MuscleParameters& p, double activation);

/// z = (F_S / cos(phi) - Phi_P(L_M)) / (max(a, floor) Fmax f(L_M)) at the muscle length along
/// the tendon x = L - L_S. Finite for every finite input: f is floored at 1e-12 (an absurd fibre
/// length underflows exp), cos(phi) at 1e-2 (a fibre squeezed to its thickness).
double force_ratio(const MuscleParameters& p, double tendon_force_N, double activation,
                   double along_tendon_m);

/// Fibre shortening velocity u = g^-1(z) along the fibre, of the forward model (safe
/// extension included).
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

// ---- Activation dynamics: da/dt = sigma(n) (n - a), sigma(n) = (beta + (1 - beta) n) / T_act.
double activation_rate_factor(const MuscleParameters& p, double excitation);  ///< sigma, 1/s
double activation_derivative(const MuscleParameters& p, double excitation, double activation);
double activation_derivative_d_excitation(const MuscleParameters& p, double excitation,
                                          double activation);
double activation_derivative_d_activation(const MuscleParameters& p, double excitation,
                                          double activation);

/// Result of inverting the activation dynamics.
struct ExcitationFromActivation {
  double excitation = 0.0;  ///< the larger real root (the one in [0,1] when attainable)
  bool real_root = true;    ///< false: no excitation gives this da/dt; excitation is then the
                            ///< minimiser of |da/dt(n) - target|, which is not a solution
  bool in_unit_interval() const { return real_root && excitation >= 0.0 && excitation <= 1.0; }
};

/// Excitation n with sigma(n) (n - a) = da/dt: the larger root of
/// (1 - beta) n^2 + (beta - (1 - beta) a) n - beta a - T_act da/dt = 0.
/// For a in [0, 1] and da/dt = 0 it returns n = a (the other root is negative). The roots sum
/// to a - beta / (1 - beta): for a > beta / (1 - beta) (1/3 with the default time constants)
/// sigma(n) (n - a) is not monotone in n and two excitations in [0, 1] can give the same
/// da/dt; the larger root is returned because it varies continuously along a trajectory.
ExcitationFromActivation excitation_from_activation(const MuscleParameters& p, double activation,
                                                    double activation_rate_per_s);

/// The excitation bounds as smooth (C1) conditions on (a, da/dt): for a in (0, 1], the larger
/// root n of the inverse activation dynamics is real and in [0, 1] exactly when both margins
/// are >= 0:
///   lower = T_act (da/dt - min_{n in [0, 1]} sigma(n) (n - a))
///         = T_act da/dt + beta a                          for a <= beta / (1 - beta),
///           T_act da/dt + (beta + (1 - beta) a)^2 / (4 (1 - beta))  above (there the fastest
///           deactivation is not at n = 0: sigma(n) (n - a) has its minimum at n > 0);
///   upper = 1 - a - T_act da/dt  (no faster activation than n = 1 gives).
/// Unlike n itself they are defined for every da/dt (no root to lose), so an optimizer can
/// impose them from any start. With their partial derivatives.
struct ExcitationBoundMargins {
  double lower = 0.0, upper = 0.0;
  double lower_d_activation = 0.0, lower_d_rate_s = 0.0;
  double upper_d_activation = 0.0, upper_d_rate_s = 0.0;
};
ExcitationBoundMargins excitation_bound_margins(const MuscleParameters& p, double activation,
                                                double activation_rate_per_s);

}  // namespace flatsos::muscles
