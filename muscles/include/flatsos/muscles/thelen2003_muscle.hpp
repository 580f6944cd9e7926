#pragma once
// Thelen's (2003) muscle as OpenSim's Thelen2003Muscle defines it (Thelen, "Adjustment of muscle
// mechanics model parameters to simulate dynamic contractions in older adults", J Biomech Eng
// 125:70-77, 2003). The MuscleParameters fields it reads, by OpenSim's property names:
//   tendon_strain_at_max_force        FmaxTendonStrain e0 (0.04)
//   force_length_width                sqrt(KshapeActive) (sqrt(0.45))
//   passive_fiber_strain_at_one_norm_force  FmaxMuscleStrain (0.6; 0: no passive force)
//   passive_force_length_shape        KshapePassive (5)
//   hill_constant                     Af (0.25)
//   max_eccentric_force_ratio         Flen (1.4)
//   max_shortening_velocity_in_optimal_lengths_per_s  max_contraction_velocity (10)
//   activation_time_constant_s, deactivation_time_constant_s  (0.015, 0.05)
//   activation_floor                  minimum_activation (0.01)
// The laws, in normalized units (tendon strain e = L_S / L_slack - 1, fibre length l = L_M / Lopt):
//   tendon   F / Fmax = Ftoe (exp(kToe e / eToe) - 1) / (exp(kToe) - 1) for 0 < e <= eToe,
//            klin (e - eToe) + Ftoe above; kToe = 3, Ftoe = 0.33, and eToe (about 0.609 e0) and klin
//            (about 1.712 / e0) exactly such that F(e0) = Fmax with a continuous slope;
//   active   f = exp(-(l - 1)^2 / KshapeActive);
//   passive  Fmax (exp(KshapePassive (l - 1) / e0) - 1) / (exp(KshapePassive) - 1) for l > 1;
//   velocity Thelen's inverse: the shortening velocity from the force ratio z, at full activation,
//            u / Vmax = (1 - z) / (1 + z / Af)                               for z <= 1,
//            u / Vmax = -(z - 1) (Flen - 1) / ((2 + 2 / Af) (Flen - z))      for z > 1,
//            continued linearly above z = 0.95 Flen (fv_linear_extrap_threshold) and below 0;
//            g is the inverse of all of it (continuous at u = 0, its slope doubles there), so the
//            forward model is exact at every force ratio (forceRatioExactUpperBound is infinite);
//   activation da/dt = (n - a) / tau, tau = T_act (0.5 + 1.5 a) when n > a, T_deact / (0.5 + 1.5 a)
//            otherwise, with a clamped to [minimum_activation, 1] (n is not, as in OpenSim 4); the
//            excitation's own bounds are [minimum_activation, 1] (OpenSim's min_control).
//   maximum velocity Vmax (0.25 + 0.75 a): g at activation a is g(u / (0.25 + 0.75 a)) (k(a),
//            muscle_model.hpp), as OpenSim scales the shortening velocity it computes.
// Not yet as OpenSim: OpenSim caps pennation at acos(0.1) where the shared geometry lets cos(phi)
// fall to 0.01.

#include "flatsos/muscles/muscle_model.hpp"

namespace flatsos::muscles {

class Thelen2003Muscle final : public MuscleModel {
 public:
  static constexpr const char* kName = "thelen2003";
  std::string name() const override { return kName; }
  /// Af > 0, Flen > 1, KshapeActive > 0, KshapePassive > 0.
  void validate(const MuscleParameters& p) const override;
  /// The fields above at OpenSim's defaults.
  void setDefaults(MuscleParameters& p) const override;
  std::string slopeJumps() const override;
  double minimumExcitation(const MuscleParameters& p) const override { return p.activation_floor; }

  CurveJet tendonForce(const MuscleParameters& p, double tendon_length_m) const override;
  double tendonForceThirdDerivative(const MuscleParameters& p, double tendon_length_m) const override;
  double tendonLengthFromForce(const MuscleParameters& p, double tendon_force_N) const override;

  CurveJet activeForceLength(const MuscleParameters& p, double fiber_length_m) const override;
  CurveJet passiveFiberForce(const MuscleParameters& p, double fiber_length_m) const override;
  CurveJet forceVelocity(const MuscleParameters& p, double shortening_velocity_m_per_s) const override;
  double forceVelocityInverse(const MuscleParameters& p, double force_ratio) const override;
  double forceRatioExactUpperBound(const MuscleParameters& p) const override;
  CurveJet fiberVelocityFromForceRatio(const MuscleParameters& p, double force_ratio) const override;
  /// k(a) = 0.25 + 0.75 a: Thelen's maximum shortening velocity falls to a quarter at rest.
  CurveJet maxVelocityScale(const MuscleParameters&, double activation) const override {
    return {0.25 + 0.75 * activation, 0.75, 0.0};
  }
  bool scalesMaxVelocityWithActivation() const override { return true; }

  ActivationRate activationRate(const MuscleParameters& p, double excitation, double activation) const override;
  ExcitationFromActivation excitationFromActivation(const MuscleParameters& p, double activation,
                                                    double activation_rate_per_s) const override;
  /// lower = (n at da/dt) - minimum_activation scaled by the time constant, upper = 1 - n scaled
  /// likewise, each in the branch (activation or deactivation) where it can be violated.
  ExcitationBoundMargins excitationBoundMargins(const MuscleParameters& p, double activation,
                                                double activation_rate_per_s) const override;
};

}  // namespace flatsos::muscles
