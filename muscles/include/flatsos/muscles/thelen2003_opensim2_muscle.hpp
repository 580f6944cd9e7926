#pragma once
// Thelen's (2003) muscle as OpenSim 2.x (2010-2011) implemented Thelen2003Muscle, the model behind
// results written then, such as the arm26 tutorial's forward simulation (Thelen, J Biomech Eng
// 125:70-77, 2003; OpenSim 2.x's reading of it). OpenSim 4's version (thelen2003_muscle.hpp)
// changed most of its laws; this one is for reproducing such results, through the importer's
// opensim_2_muscles option. Its differences, in normalized units (l = L_M / Lopt, tendon strain
// e = L_S / L_slack - 1, e0 the tendon's strain at Fmax, e0M FmaxMuscleStrain):
//   activation da/dt = (n - a) / T_act when n >= a, else (n - a) / T_deact: constant time
//            constants, no minimum activation (activation_floor 1e-6 is the floor OpenSim 2.x used
//            inside the velocity law only), n as it comes;
//   passive  exp(KshapePassive (l - 1) / e0M) / exp(KshapePassive) up to l = 1 + e0M (not zero
//            below the optimal length), then linear with slope KshapePassive / e0M;
//   tendon   Thelen's toe with OpenSim 2.x's rounded constants (toe end 0.609 e0, toe force
//            0.333333, linear slope 1.712 / e0; the slope jumps at the toe's end), plus
//            0.001 (1 + e) at every strain (a slack tendon still pulls 0.001 Fmax (1 + e));
//   velocity its own law (MuscleModel::hasOwnVelocityLaw): with Fa = max(a, 1e-6) f(l), Fv =
//            A / Fmax (A = F / cos - Phi_P) and d the fibre damping (OpenSim 2.x's 0.05), the
//            lengthening velocity per Vmax(a) = (Vmax0 + a (Vmax - Vmax0)) Lopt, Vmax0 = 5 / s, is
//              (Fv - Fa) / (Fa + Fv / Af + d)          0 <= Fv < Fa,
//              (Fv - Fa) / (b(Fv) + d)                 Fa <= Fv < 0.95 Fa Flen,
//            b(F) = (2 + 2 / Af) (Fa Flen - F) / (Flen - 1), each continued linearly beyond (below
//            Fv = 0 and above 0.95 Fa Flen) with the slope OpenSim 2.x took by a difference of
//            1e-6 in force.
// Planning with it uses Thelen's undamped law at the same k(a) = 0.5 + 0.5 a (the shared laws
// below), so a plan is not exactly what this model simulates.

#include "flatsos/muscles/muscle_model.hpp"
#include "flatsos/muscles/thelen2003_muscle.hpp"

namespace flatsos::muscles {

class Thelen2003OpenSim2Muscle final : public MuscleModel {
 public:
  static constexpr const char* kName = "thelen2003_opensim2";
  /// OpenSim 2.x's Vmax0 (optimal lengths per s at zero activation); OpenSim 4 files do not carry it.
  static constexpr double kMaxVelocityAtRestInOptimalLengthsPerS = 5.0;
  std::string name() const override { return kName; }
  void validate(const MuscleParameters& p) const override;
  /// OpenSim 2.x's defaults (tendon e0 0.033, KshapeActive 0.5, KshapePassive 4, Af 0.3, Flen 1.8,
  /// damping 0.05, time constants 0.01 and 0.04 s, Vmax 10 / s).
  void setDefaults(MuscleParameters& p) const override;
  std::string slopeJumps() const override;

  CurveJet tendonForce(const MuscleParameters& p, double tendon_length_m) const override;
  double tendonForceThirdDerivative(const MuscleParameters& p, double tendon_length_m) const override;
  double tendonLengthFromForce(const MuscleParameters& p, double tendon_force_N) const override;

  CurveJet activeForceLength(const MuscleParameters& p, double fiber_length_m) const override;
  CurveJet passiveFiberForce(const MuscleParameters& p, double fiber_length_m) const override;
  CurveJet forceVelocity(const MuscleParameters& p, double u) const override { return undamped_.forceVelocity(p, u); }
  double forceVelocityInverse(const MuscleParameters& p, double z) const override { return undamped_.forceVelocityInverse(p, z); }
  double forceRatioExactUpperBound(const MuscleParameters& p) const override { return undamped_.forceRatioExactUpperBound(p); }
  CurveJet fiberVelocityFromForceRatio(const MuscleParameters& p, double z) const override {
    return undamped_.fiberVelocityFromForceRatio(p, z);
  }
  /// k(a) = (Vmax0 + a (Vmax - Vmax0)) / Vmax.
  CurveJet maxVelocityScale(const MuscleParameters& p, double activation) const override;
  bool scalesMaxVelocityWithActivation() const override { return true; }
  bool hasOwnVelocityLaw() const override { return true; }
  OwnFiberVelocity ownFiberVelocity(const MuscleParameters& p, double activation, double fiber_length_m,
                                    double fiber_force_N) const override;

  ActivationRate activationRate(const MuscleParameters& p, double excitation, double activation) const override;
  ExcitationFromActivation excitationFromActivation(const MuscleParameters& p, double activation,
                                                    double activation_rate_per_s) const override;
  ExcitationBoundMargins excitationBoundMargins(const MuscleParameters& p, double activation,
                                                double activation_rate_per_s) const override;

 private:
  Thelen2003Muscle undamped_;  // Thelen's undamped velocity law, for planning
};

}  // namespace flatsos::muscles
