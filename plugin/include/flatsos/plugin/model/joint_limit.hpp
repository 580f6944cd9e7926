#pragma once
// A joint's passive limit torque, in the manner of OpenSim's CoordinateLimitForce: zero inside the
// range of motion; beyond either end a spring and a damper that engage together over a transition
// width. With penetration x beyond the nearer end and the smooth step
// s(x) = 10 u^3 - 15 u^4 + 6 u^5, u = x / transition (0 at the range's end, 1 from the end of the
// transition on), the torque pushes back into the range:
//   tau = -sign * s(x) (k x + c * sign * qd),  sign = +1 beyond the upper end, -1 below the lower.
// s is twice continuously differentiable, so the torque is too (in q), and its second time
// derivative along a smooth motion is continuous: the planner's inverse map needs exactly that.
// The elastic part has the potential V(x) = k transition^2 P(u), P(u) = 2 u^5 - 5/2 u^6 + 6/7 u^7
// below the transition's end and V = k (5/14 transition^2 + (x^2 - transition^2) / 2) beyond.
// Written once for any scalar type (dual numbers give exact derivatives).

#include "flatsos/plugin/model/dual_number.hpp"

namespace flatsos::plugin {

struct JointLimitTorque {
  double stiffness_N_m_per_rad = 0.0;  ///< k > 0 enables the limit
  double transition_rad = 0.0;         ///< width over which spring and damper engage (> 0)
  double damping_N_m_s_per_rad = 0.0;  ///< c >= 0
  bool enabled() const { return stiffness_N_m_per_rad > 0.0; }
};

namespace detail {
/// 10 u^3 - 15 u^4 + 6 u^5 on [0, 1], 1 beyond: value, first and second derivative vanish at 0
/// and the derivatives at 1.
template <class S>
S limit_smooth_step(const S& u) {
  if (primal(u) >= 1.0) return S(1.0);
  const S u3 = u * u * u;
  return u3 * (S(10.0) + u * (S(-15.0) + u * S(6.0)));
}
}  // namespace detail

/// The limit torque at angle q and speed qd for the range [lower, upper] (rad, N m).
template <class S>
S joint_limit_torque(const JointLimitTorque& limit, double lower_rad, double upper_rad, const S& q_rad,
                     const S& qd_rad_per_s) {
  if (!limit.enabled()) return S(0.0);
  const double q = primal(q_rad);
  const double sign = q > upper_rad ? 1.0 : q < lower_rad ? -1.0 : 0.0;
  if (sign == 0.0) return S(0.0);
  const S x = sign > 0.0 ? q_rad - S(upper_rad) : S(lower_rad) - q_rad;  // penetration >= 0
  const S s = detail::limit_smooth_step(x / S(limit.transition_rad));
  return S(-sign) * s * (S(limit.stiffness_N_m_per_rad) * x + S(sign * limit.damping_N_m_s_per_rad) * qd_rad_per_s);
}

/// The elastic part's potential energy (J) at angle q: the work the spring returns on the way back
/// into the range (the damper's share is lost).
inline double joint_limit_potential_energy(const JointLimitTorque& limit, double lower_rad, double upper_rad,
                                           double q_rad) {
  if (!limit.enabled()) return 0.0;
  const double x = q_rad > upper_rad ? q_rad - upper_rad : q_rad < lower_rad ? lower_rad - q_rad : 0.0;
  const double w = limit.transition_rad, k = limit.stiffness_N_m_per_rad;
  if (x >= w) return k * (5.0 / 14.0 * w * w + 0.5 * (x * x - w * w));
  const double u = x / w;
  return k * w * w * u * u * u * u * u * (2.0 + u * (-2.5 + u * 6.0 / 7.0));
}

}  // namespace flatsos::plugin
