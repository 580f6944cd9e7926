#pragma once
// De Groote, Kinney, Rao and Fregly's (2016) muscle as OpenSim's DeGrooteFregly2016Muscle (the
// muscle of OpenSim Moco) defines it (De Groote F, Kinney AL, Rao AV, Fregly BJ, "Evaluation of
// direct collocation optimal control problem formulations for solving the muscle redundancy
// problem", Ann Biomed Eng 44:2922-2936, 2016). Every law is smooth, so gradient-based
// optimizers over the muscle's states (the collocation reference) converge with it.
// The MuscleParameters fields it reads, by OpenSim's property names:
//   tendon_strain_at_max_force        tendon_strain_at_one_norm_force e0 (0.049)
//   force_length_width                active_force_width_scale (1)
//   passive_fiber_strain_at_one_norm_force  passive_fiber_strain_at_one_norm_force (0.6; 0 as
//                                     ignore_passive_fiber_force)
//   passive_force_length_shape        kPE (4, a constant in OpenSim)
//   max_shortening_velocity_in_optimal_lengths_per_s  max_contraction_velocity (10)
//   activation_time_constant_s, deactivation_time_constant_s  (0.015, 0.060)
//   activation_dynamics_smoothing     activation_dynamics_smoothing b (0.1)
// The laws, in normalized units (tendon length l_T = L_S / L_slack, fibre length l = L_M / Lopt,
// lengthening velocity v = -u / Vmax):
//   tendon   F / Fmax = c1 exp(kT (l_T - c2)) - c3, c1 = c3 = 0.2, c2 = 1, kT = ln(6) / e0: 0 at
//            slack, Fmax at e0, a small compression (down to -0.2 Fmax) below slack, as in OpenSim;
//   active   sum of three Gaussian-like curves b1 exp(-(x - b2)^2 / (2 (b3 + b4 x)^2)) of
//            x = (l - 1) / scale + 1, with OpenSim's coefficients (f(1) = 1);
//   passive  Fmax (exp(kPE (l - 1) / e0) - o) / (exp(kPE) - o), o = exp(kPE (0.2 - 1) / e0): zero at
//            the model's least fibre length 0.2 Lopt;
//   velocity g = d1 asinh(d2 v + d3) + d4 with OpenSim's d1..d4 (g(-1) = 0, g(0) = 1, g(1) = 1.794),
//            inverse v = (sinh((g - d4) / d1) - d3) / d2;
//   activation da/dt = [(f + 1/2) / (T_act s) + (1/2 - f) s / T_deact] (n - a), s = 1/2 + 3/2 a,
//            f = tanh(b (n - a)) / 2: the switch between Thelen's two time constants smoothed.
// Not as OpenSim: the forward model's inverse of g continues linearly outside OpenSim's domain
// v in [-1, 1] (g in [0, 1.794]) where sinh would grow exponentially. Fibre damping is the
// seam's (MuscleParameters::fiber_damping, OpenSim's form; its default is 0).

#include "flatsos/muscles/muscle_model.hpp"

namespace flatsos::muscles {

class DeGrooteFregly2016Muscle final : public MuscleModel {
 public:
  static constexpr const char* kName = "degroote_fregly2016";
  std::string name() const override { return kName; }
  /// scale >= 1 as OpenSim asks, e0 > 0, kPE > 0, b > 0.
  void validate(const MuscleParameters& p) const override;
  /// The fields above at OpenSim's defaults.
  void setDefaults(MuscleParameters& p) const override;
  std::string slopeJumps() const override { return {}; }

  CurveJet tendonForce(const MuscleParameters& p, double tendon_length_m) const override;
  double tendonForceThirdDerivative(const MuscleParameters& p, double tendon_length_m) const override;
  double tendonLengthFromForce(const MuscleParameters& p, double tendon_force_N) const override;

  CurveJet activeForceLength(const MuscleParameters& p, double fiber_length_m) const override;
  CurveJet passiveFiberForce(const MuscleParameters& p, double fiber_length_m) const override;
  CurveJet forceVelocity(const MuscleParameters& p, double shortening_velocity_m_per_s) const override;
  double forceVelocityInverse(const MuscleParameters& p, double force_ratio) const override;
  /// g at v = 1 (lengthening at Vmax), 1.794: the end of OpenSim's domain.
  double forceRatioExactUpperBound(const MuscleParameters& p) const override;
  CurveJet fiberVelocityFromForceRatio(const MuscleParameters& p, double force_ratio) const override;

  ActivationRate activationRate(const MuscleParameters& p, double excitation, double activation) const override;
  /// By safeguarded Newton steps on n (rate(n, a) increases in n on [0, 1]).
  ExcitationFromActivation excitationFromActivation(const MuscleParameters& p, double activation,
                                                    double activation_rate_per_s) const override;
  /// lower = (da/dt - rate(0, a)) T_deact, upper = (rate(1, a) - da/dt) T_act.
  ExcitationBoundMargins excitationBoundMargins(const MuscleParameters& p, double activation,
                                                double activation_rate_per_s) const override;
};

}  // namespace flatsos::muscles
