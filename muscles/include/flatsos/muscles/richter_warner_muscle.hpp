#pragma once
// Richter & Warner's muscle (the paper's laws, docs/method/flatness.md), the default model:
//   tendon       F_S = k (L_S - L_slack)^2 above slack, k = Fmax / (strain_at_Fmax L_slack)^2;
//   force-length f = exp(-((L_M - Lopt) / (W Lopt))^2), W = force_length_width;
//   force-velocity Hill's hyperbola, g(u) = Ah (Vmax - u) / (Ah Vmax + u) for u >= 0, and an
//                eccentric branch rising to gmax = max_eccentric_force_ratio; the forward model
//                continues its inverse linearly beyond 1 + 0.9 (gmax - 1) and below 0;
//   passive      Fmax (e^y - 1 - y - y^2/2) / (e^k - 1 - k - k^2/2), y = k (L_M / Lopt - 1) / e0 > 0,
//                k = passive_force_length_shape (4): the exponential growth of Thelen (2003), but
//                C2 at the optimal length, where Thelen's curve has a kink;
//   activation   da/dt = sigma(n) (n - a), sigma(n) = (beta + (1 - beta) n) / T_act,
//                beta = T_act / T_deact; its inverse is the larger root of a quadratic.

#include "flatsos/muscles/muscle_model.hpp"

namespace flatsos::muscles {

class RichterWarnerMuscle final : public MuscleModel {
 public:
  static constexpr const char* kName = "richter_warner";
  std::string name() const override { return kName; }
  /// gmax > 1, Ah > 0, W > 0, T_act <= T_deact.
  void validate(const MuscleParameters& p) const override;
  /// MuscleParameters' own defaults (the paper's arm).
  void setDefaults(MuscleParameters& p) const override;
  /// None: g is C1 at u = 0 (its curvature jumps), the tendon C1 at slack.
  std::string slopeJumps() const override { return {}; }

  CurveJet tendonForce(const MuscleParameters& p, double tendon_length_m) const override;
  double tendonForceThirdDerivative(const MuscleParameters&, double) const override { return 0.0; }
  double tendonLengthFromForce(const MuscleParameters& p, double tendon_force_N) const override;

  CurveJet activeForceLength(const MuscleParameters& p, double fiber_length_m) const override;
  CurveJet passiveFiberForce(const MuscleParameters& p, double fiber_length_m) const override;
  CurveJet forceVelocity(const MuscleParameters& p, double shortening_velocity_m_per_s) const override;
  double forceVelocityInverse(const MuscleParameters& p, double force_ratio) const override;
  double forceRatioExactUpperBound(const MuscleParameters& p) const override;
  CurveJet fiberVelocityFromForceRatio(const MuscleParameters& p, double force_ratio) const override;

  ActivationRate activationRate(const MuscleParameters& p, double excitation, double activation) const override;
  ExcitationFromActivation excitationFromActivation(const MuscleParameters& p, double activation,
                                                    double activation_rate_per_s) const override;
  /// lower = T_act (da/dt - min over n in [0, 1] of sigma(n) (n - a)): T_act da/dt + beta a for
  /// a <= beta / (1 - beta), T_act da/dt + (beta + (1 - beta) a)^2 / (4 (1 - beta)) above (the
  /// fastest deactivation is then at n > 0); upper = 1 - a - T_act da/dt.
  ExcitationBoundMargins excitationBoundMargins(const MuscleParameters& p, double activation,
                                                double activation_rate_per_s) const override;
};

}  // namespace flatsos::muscles
