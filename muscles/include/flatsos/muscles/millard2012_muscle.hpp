#pragma once
// OpenSim's Millard2012EquilibriumMuscle (Millard, Uchida, Seth & Delp, "Flexing computational
// muscle: modeling and simulation of musculotendon dynamics", J Biomech Eng 135(2):021005, 2013)
// behind the muscle-model seam. Its curves are the quintic Bezier curves of
// millard2012_curves.hpp, so one instance carries one muscle's curve properties: muscles with
// different curves are different instances (std::make_shared<Millard2012Muscle>(curves,
// configuration)); muscle_model_named("millard2012") is OpenSim's default (damped) muscle.
//
// The MuscleParameters fields it reads, by OpenSim's property names:
//   max_isometric_force, optimal_fiber_length, tendon_slack_length, pennation_angle_at_optimal
//   max_contraction_velocity          max_shortening_velocity_in_optimal_lengths_per_s (10)
//   activation_time_constant, deactivation_time_constant  (0.010, 0.040 s)
//   minimum_activation                activation_floor (0.01)
//   fiber_damping                     fiber_damping (0.1; 0 for an undamped instance)
// and two it checks against its curves, because other parts of flatsos read them as scales:
// tendon_strain_at_max_force (the tendon curve's strain_at_one_norm_force) and
// passive_fiber_strain_at_one_norm_force (the passive curve's).
//
// The laws (x normalised as in millard2012_curves.hpp; u the fibre's shortening velocity):
//   tendon   Fmax fSE(L_S / L_slack); active f = fL(L_M / Lopt); passive Fmax fPE(L_M / Lopt);
//   velocity g(u) = fV(-u / Vmax), Vmax = max_contraction_velocity Lopt, where fV is the curve
//            OpenSim's forward model uses:
//            damped   the muscle's ForceVelocityCurve (slopes at +-Vmax lowered to 0: g is flat,
//                     0 beyond Vmax and fmax beyond -Vmax). Its inverse, which the forward
//                     model needs, exists on (0, fmax) only, with infinite slopes at both ends.
//                     flatsos continues it beyond them by straight lines of fV slope sqrt(eps)
//                     (flatEndContinuationSlope()), since the shared balance is solved in z:
//                     beyond +-Vmax it then carries an active force sqrt(eps) (|v| - 1) a f Fmax
//                     where OpenSim's is 0, moving the velocity by at most sqrt(eps) a f / beta
//                     (|v| - 1) Vmax; and the balance's resolution in z (1e-15 (1 + |z|)) becomes
//                     1.6e-7 Vmax in u there. A shallower line would trade the second for the
//                     first. The forward model is g's exact inverse for z in [0, fmax) (the
//                     exact bound is the double below fmax: every u <= -Vmax gives fmax).
//            undamped the curve whose inverse OpenSim's forward model evaluates (its
//                     ForceVelocityInverseCurve): fV with each slope at Vmax half its slope near
//                     Vmax, the muscle's own ForceVelocityCurve unless a slope at Vmax was given
//                     above that. Invertible everywhere (linear beyond +-Vmax): exact at every z.
//   activation OpenSim's first-order model (MuscleFirstOrderActivationDynamicModel), as
//            Thelen2003Muscle: a clamped to [minimum_activation, 1], n in [minimum_activation, 1].
//   fibre floor  minimumFiberLength: OpenSim's clamp, max(SignificantReal, min_norm_active_fiber_length
//            Lopt, h / sin(maximum_pennation_angle)) (0.01 Lopt without maximum pennation); the
//            shared forward model holds the fibre there while it would shorten.
// The damped fL is 0 below min_norm_active_fiber_length and above max_norm_active_fiber_length
// (the seam expects f > 0): the forward model floors it as for every model, but the flatness
// inverse has no finite activation there (invert_muscle gives a = +-inf, its rate, excitation
// and gradients NaN, at stage Complete; the planner reports an activation outside [0, 1]).
// From below, the fibre floor keeps the forward model out of that region.
// Curves that depend on the configuration: OpenSim's muscle adjusts its fL minimum and fV end
// slopes to damped or undamped (millard2012_muscle_curve_parameters); an instance is built for
// one of them and validate() rejects a muscle whose fiber_damping is of the other kind.
//
// Not yet as OpenSim:
//   - a rigid tendon (ignore_tendon_compliance) and ignore_activation_dynamics: flatsos' muscles
//     have an elastic tendon and activation dynamics;
//   - minimum_activation 0 (OpenSim's damped model allows it): flatsos' activation floor is > 0;
//   - a fibre below its minimum length: OpenSim reads its fibre-length state as the minimum
//     (the tendon then takes the rest of the path); flatsos' state is the tendon length, so a
//     state whose fibre is already shorter is held where it is instead;
//   - the active and passive fibre forces OpenSim reports as 0 while the fibre is held, and
//     its fibre-velocity Newton's tolerance (1e-10 Fmax, 20 iterations, an error if it fails):
//     flatsos solves the same balance to rounding and never fails;
//   - the activation's upper clamp at 1 in the force balance (flatsos clamps only from below).

#include <cmath>

#include "flatsos/muscles/millard2012_curves.hpp"
#include "flatsos/muscles/muscle_model.hpp"

namespace flatsos::muscles {

class Millard2012Muscle final : public MuscleModel {
 public:
  static constexpr const char* kName = "millard2012";
  /// fV slope assumed beyond the damped curve's flat ends (see above): sqrt(eps), the least
  /// slope near Vmax OpenSim accepts.
  static double flatEndContinuationSlope();
  /// OpenSim's default maximum_pennation_angle, acos(0.1).
  static double defaultMaximumPennationAngle() { return std::acos(0.1); }

  /// OpenSim's default muscle: its default curves, damped (fiber_damping 0.1).
  Millard2012Muscle();
  /// A muscle with these curve properties as OpenSim's muscle adjusts them to `configuration`.
  /// Throws std::invalid_argument naming the property for bad curve properties, a rigid tendon
  /// (not supported), or a maximum pennation angle outside [0, pi/2].
  Millard2012Muscle(const Millard2012CurveParameters& curve_parameters,
                    const Millard2012MuscleConfiguration& configuration = {},
                    double maximum_pennation_angle_rad = defaultMaximumPennationAngle());

  /// True when built for fiber_damping >= 0.001 (OpenSim's damped model).
  bool damped() const { return damped_; }
  /// The properties the curves were built from: adjusted to the configuration, optional ones
  /// resolved to the values OpenSim uses.
  const Millard2012CurveParameters& curveParameters() const { return parameters_; }
  /// The muscle's curves as OpenSim builds them (force_velocity: the muscle's ForceVelocityCurve).
  const Millard2012Curves& curves() const { return curves_; }
  double maximumPennationAngle() const { return maximum_pennation_angle_rad_; }

  std::string name() const override { return kName; }
  /// fiber_damping of this instance's kind (>= 0.001 damped, exactly 0 undamped), activation_floor
  /// >= 0.01 undamped (OpenSim's check), and the two strains above equal to the curves' own.
  void validate(const MuscleParameters& p) const override;
  /// OpenSim's defaults for the fields above; the strains and fiber_damping from this instance.
  void setDefaults(MuscleParameters& p) const override;
  std::string slopeJumps() const override;
  double minimumExcitation(const MuscleParameters& p) const override { return p.activation_floor; }
  double minimumFiberLength(const MuscleParameters& p) const override;

  CurveJet tendonForce(const MuscleParameters& p, double tendon_length_m) const override;
  double tendonForceThirdDerivative(const MuscleParameters& p, double tendon_length_m) const override;
  double tendonLengthFromForce(const MuscleParameters& p, double tendon_force_N) const override;

  CurveJet activeForceLength(const MuscleParameters& p, double fiber_length_m) const override;
  CurveJet passiveFiberForce(const MuscleParameters& p, double fiber_length_m) const override;
  CurveJet forceVelocity(const MuscleParameters& p, double shortening_velocity_m_per_s) const override;
  /// Damped: defined on (0, fmax), where g is one to one; undamped: every finite z.
  double forceVelocityInverse(const MuscleParameters& p, double force_ratio) const override;
  double forceRatioExactUpperBound(const MuscleParameters& p) const override;
  CurveJet fiberVelocityFromForceRatio(const MuscleParameters& p, double force_ratio) const override;

  ActivationRate activationRate(const MuscleParameters& p, double excitation, double activation) const override;
  ExcitationFromActivation excitationFromActivation(const MuscleParameters& p, double activation,
                                                    double activation_rate_per_s) const override;
  ExcitationBoundMargins excitationBoundMargins(const MuscleParameters& p, double activation,
                                                double activation_rate_per_s) const override;

 private:
  CurveJet flatEndInverse(const MuscleParameters& p, double force_ratio) const;

  Millard2012CurveParameters parameters_;
  bool damped_;
  double damping_;  ///< the configuration's fiber_damping if damped, else 0
  double maximum_pennation_angle_rad_;
  Millard2012Curves curves_;
  /// g's curve in OpenSim's normalised lengthening velocity (see above).
  QuinticBezierCurve velocity_curve_;
};

}  // namespace flatsos::muscles
