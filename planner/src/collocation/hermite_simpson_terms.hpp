#pragma once
// What the Hermite-Simpson transcription's values and derivatives share (hermite_simpson.hpp):
// the defects' weights, a muscle's factors at a point, and the joint defects' terms.

#include <array>

#include "collocation/hermite_simpson.hpp"

namespace flatsos::planner::detail {
inline constexpr double kInfinity = 1e19;  // Ipopt's default for "no bound"

// The muscle model's activation dynamics f_a(n, a) with its partial derivatives.
inline muscles::ActivationRate activation_rate(const muscles::MuscleParameters& p, double n, double a) {
  return p.model->activationRate(p, n, a);
}

// Simpson's and the interpolation defect's weights of f at the interval's first, middle and
// last point, in units of the interval length h.
inline constexpr std::array<double, 3> kSimpsonRate = {-1.0 / 6.0, -4.0 / 6.0, -1.0 / 6.0};
inline constexpr std::array<double, 3> kInterpolationRate = {-1.0 / 8.0, 0.0, 1.0 / 8.0};
// ... and of the state itself.
inline constexpr std::array<double, 3> kSimpsonState = {-1.0, 0.0, 1.0};
inline constexpr std::array<double, 3> kInterpolationState = {-0.5, 1.0, -0.5};

// Tendon force, force-length and force-velocity factors at a point, with their derivatives with
// respect to the scaled unknowns s (tendon stretch) and v (shortening velocity / Vmax).
struct HermiteSimpsonProblem::MuscleAt {
  double s, a, n, v;
  double F, F_s, F_ss;  // N
  double f, f_s, f_ss;
  double f_L, f_LL;  // with respect to the fibre length (a free path moves it through q)
  double g, g_v, g_vv;
};

template <class Term>
void HermiteSimpsonProblem::visitJointDefect(int k, int r, int which, Term&& term) const {
  const auto& state = which % 2 == 0 ? kSimpsonState : kInterpolationState;
  const auto& rate = which % 2 == 0 ? kSimpsonRate : kInterpolationRate;
  const JointUnknown y = which < 2 ? kAngle : kSpeed, dy = which < 2 ? kSpeed : kAcceleration;
  for (int c = 0; c < 3; ++c) {
    if (state[c] != 0.0) term(jointIndex(2 * k + c, r, y), state[c]);
    if (rate[c] != 0.0) term(jointIndex(2 * k + c, r, dy), intervalLength(k) * rate[c]);
  }
}

}  // namespace flatsos::planner::detail
