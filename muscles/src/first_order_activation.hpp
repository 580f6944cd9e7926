#pragma once
// OpenSim's MuscleFirstOrderActivationDynamicModel (Thelen 2003's activation dynamics; used by
// Thelen2003Muscle and Millard2012EquilibriumMuscle alike), shared by the models that follow it:
//   da/dt = (n - a) / tau,  tau = T_act (0.5 + 1.5 a) when n > a, T_deact / (0.5 + 1.5 a) otherwise,
// with a clamped to [minimum_activation, 1] (p.activation_floor) and n not clamped (OpenSim 4);
// the excitation's own bounds are [minimum_activation, 1] (OpenSim's min_control).

#include <algorithm>

#include "flatsos/muscles/muscle_model.hpp"

namespace flatsos::muscles::detail {

/// The activation the dynamics use: clamped to [minimum_activation, 1].
inline double first_order_clamped_activation(const MuscleParameters& p, double activation) {
  return std::clamp(activation, p.activation_floor, 1.0);
}

inline ActivationRate first_order_activation_rate(const MuscleParameters& p, double excitation, double activation) {
  const double n = excitation, a = first_order_clamped_activation(p, activation);
  // Partial derivatives are those of the clamped law: 0 across a clamped activation.
  const double dn = 1.0, da = a == activation ? 1.0 : 0.0;
  const double s = 0.5 + 1.5 * a;
  ActivationRate r;
  if (n > a) {  // activation: (n - a) / (T_act s)
    const double T = p.activation_time_constant_s;
    r.value = (n - a) / (T * s);
    r.d_excitation = dn / (T * s);
    r.d_activation = da * -(0.5 + 1.5 * n) / (T * s * s);
    r.d_excitation_activation = dn * da * -1.5 / (T * s * s);
    r.d_activation2 = da * 3.0 * (0.5 + 1.5 * n) / (T * s * s * s);
  } else {  // deactivation: (n - a) s / T_deact
    const double T = p.deactivation_time_constant_s;
    r.value = (n - a) * s / T;
    r.d_excitation = dn * s / T;
    r.d_activation = da * (1.5 * (n - a) - s) / T;
    r.d_excitation_activation = dn * da * 1.5 / T;
    r.d_activation2 = da * -3.0 / T;
  }
  return r;
}

inline ExcitationFromActivation first_order_excitation_from_activation(const MuscleParameters& p, double activation,
                                                                       double rate) {
  const double a = first_order_clamped_activation(p, activation);
  const double da = a == activation ? 1.0 : 0.0;
  const double s = 0.5 + 1.5 * a;
  ExcitationFromActivation out;
  if (rate > 0.0) {
    const double T = p.activation_time_constant_s;
    out.excitation = a + rate * T * s;
    out.d_activation = da * (1.0 + 1.5 * rate * T);
    out.d_activation_rate_s = T * s;
  } else {
    const double T = p.deactivation_time_constant_s;
    out.excitation = a + rate * T / s;
    out.d_activation = da * (1.0 - 1.5 * rate * T / (s * s));
    out.d_activation_rate_s = T / s;
  }
  return out;
}

inline ExcitationBoundMargins first_order_excitation_bound_margins(const MuscleParameters& p, double activation,
                                                                   double rate) {
  // n = a + rate T_act s (rate > 0) or a + rate T_deact / s (rate <= 0), s = 0.5 + 1.5 a. The
  // lower bound can fail only while deactivating, the upper only while activating; each margin
  // is n - minimum or 1 - n of its own branch, smooth in (a, rate) and positive across the other
  // branch for a in [minimum, 1].
  const double a = activation, s = 0.5 + 1.5 * a;
  const double Ta = p.activation_time_constant_s, Td = p.deactivation_time_constant_s;
  ExcitationBoundMargins m;
  m.lower = a - p.activation_floor + rate * Td / s;
  m.lower_d_activation = 1.0 - 1.5 * rate * Td / (s * s);
  m.lower_d_rate_s = Td / s;
  m.upper = 1.0 - a - rate * Ta * s;
  m.upper_d_activation = -1.0 - 1.5 * rate * Ta;
  m.upper_d_rate_s = -Ta * s;
  return m;
}

}  // namespace flatsos::muscles::detail
