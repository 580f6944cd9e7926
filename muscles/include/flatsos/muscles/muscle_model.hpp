#pragma once
// The muscle-model seam: the laws of one kind of Hill-type muscle behind one interface. The
// Simbody force element, the flatness planner's inverse map and bounds, static equilibrium and
// the collocation reference call a muscle's laws only through its MuscleParameters::model, so a
// new kind of muscle is one new implementation of this class (registered by name in
// muscle_models.cpp), not a copy of each caller.
//
// What every model shares, and so is not a law here: the fibre's force acts as
//   F_S = (a Fmax f(L_M) g(u / k(a)) + Phi_P(L_M) + D(u)) cos(phi)
// on the tendon, with pennation at constant fibre thickness (hill_laws.hpp), the fibre's
// damping D(u) = -beta Fmax u / Vmax (MuscleParameters::fiber_damping; 0 without), and the
// activation a in [0, 1] following da/dt = rate(n, a) from the excitation n in [0, 1]. k(a) =
// Vmax(a) / Vmax is 1 unless the model's maximum shortening velocity depends on activation.
//
// Units: SI (m, m/s, N, s). u is the fibre's *shortening* velocity (u > 0 concentric).

#include <memory>
#include <string>
#include <vector>

#include "flatsos/muscles/muscle_parameters.hpp"

namespace flatsos::muscles {

/// A law's value with its first and second derivatives with respect to its argument.
struct CurveJet {
  double value = 0.0, slope = 0.0, curvature = 0.0;
};

/// da/dt = rate(n, a) with its partial derivatives (1/s).
struct ActivationRate {
  double value = 0.0;
  double d_excitation = 0.0, d_activation = 0.0;
  double d_excitation2 = 0.0, d_excitation_activation = 0.0, d_activation2 = 0.0;
};

/// The inverse of the activation dynamics: n with rate(n, a) = da/dt.
struct ExcitationFromActivation {
  double excitation = 0.0;
  bool real_root = true;  ///< false: no excitation gives this da/dt; excitation is then the
                          ///< closest the model has, which is not a solution
  /// dn/da and dn/d(da/dt) (s) where real_root.
  double d_activation = 0.0, d_activation_rate_s = 0.0;
  bool in_unit_interval() const { return real_root && excitation >= 0.0 && excitation <= 1.0; }
};

/// The excitation bounds as smooth conditions on (a, da/dt): for a in (0, 1], an excitation in
/// [MuscleModel::minimumExcitation, 1] gives this da/dt exactly when lower >= 0 and upper >= 0. Unlike n they are defined for
/// every da/dt, so an optimizer can impose them from any start. With their partial derivatives.
struct ExcitationBoundMargins {
  double lower = 0.0, upper = 0.0;
  double lower_d_activation = 0.0, lower_d_rate_s = 0.0;
  double upper_d_activation = 0.0, upper_d_rate_s = 0.0;
};

/// A fibre velocity from a model's own law, with its partial derivatives.
struct OwnFiberVelocity {
  double shortening_m_per_s = 0.0;
  double d_fiber_force = 0.0;  ///< per N of A = F / cos - Phi_P, m/s/N
  double d_activation = 0.0;   ///< m/s
  double d_fiber_length = 0.0; ///< 1/s
};

class MuscleModel {
 public:
  virtual ~MuscleModel() = default;

  /// The name a model file gives ("muscle_model"): lower case, stable.
  virtual std::string name() const = 0;
  /// Throws std::invalid_argument naming the muscle and the field for a parameter this model
  /// cannot use (the shared checks are in validate(MuscleParameters)).
  virtual void validate(const MuscleParameters& p) const = 0;
  /// Sets the fields this model reads, other than the muscle's name, Fmax, optimal fibre length,
  /// tendon slack length and pennation, to the model's published defaults: what a model file
  /// starts from when it names the model.
  virtual void setDefaults(MuscleParameters& p) const = 0;
  /// Where a law's first derivative jumps, in words ("force-velocity slope doubles at u = 0"),
  /// or empty when every law has a continuous slope. Gradient-based optimizers over the
  /// muscle's states (the collocation reference) cannot converge across such jumps.
  virtual std::string slopeJumps() const = 0;
  /// The least excitation the muscle accepts (its control's lower bound); the upper is 1.
  virtual double minimumExcitation(const MuscleParameters&) const { return 0.0; }
  /// The fibre length (m) the forward model does not let the fibre shorten below (OpenSim's
  /// Millard muscle clamps its fibre there): a fibre below it, or at it and shortening, holds its
  /// length (u = 0) and the tendon takes the path's motion. 0: no such floor.
  virtual double minimumFiberLength(const MuscleParameters&) const { return 0.0; }

  // ---- Tendon: force from its length (0 at slack; below slack 0, or a model's small
  // compression), and the inverse for forces > 0.
  virtual CurveJet tendonForce(const MuscleParameters& p, double tendon_length_m) const = 0;
  /// d3 F_S / d L_S^3 (N/m^3): the inverse map's exact gradients need it.
  virtual double tendonForceThirdDerivative(const MuscleParameters& p, double tendon_length_m) const = 0;
  /// Throws std::domain_error for a force that is not finite and > 0.
  virtual double tendonLengthFromForce(const MuscleParameters& p, double tendon_force_N) const = 0;

  // ---- Fibre.
  /// Active force-length factor f(L_M) > 0: 1 at the optimal length, its peak near 1.
  virtual CurveJet activeForceLength(const MuscleParameters& p, double fiber_length_m) const = 0;
  /// Passive fibre force Phi_P(L_M) in N (0 for a model or muscle without one).
  virtual CurveJet passiveFiberForce(const MuscleParameters& p, double fiber_length_m) const = 0;
  /// Force-velocity factor g(u): g(0) = 1, decreasing.
  virtual CurveJet forceVelocity(const MuscleParameters& p, double shortening_velocity_m_per_s) const = 0;
  /// Exact inverse of g; throws std::domain_error outside the range where it exists.
  virtual double forceVelocityInverse(const MuscleParameters& p, double force_ratio) const = 0;
  /// Upper end of the force ratios on which the forward model uses the exact inverse of g; a
  /// plan whose g goes above it is not what the simulation executes. Infinite for a model whose
  /// g is the inverse of its forward model everywhere.
  virtual double forceRatioExactUpperBound(const MuscleParameters& p) const = 0;
  /// The inverse of g the forward model uses (value and slope in z): finite and strictly
  /// decreasing for every finite z, exact on [0, forceRatioExactUpperBound].
  virtual CurveJet fiberVelocityFromForceRatio(const MuscleParameters& p, double force_ratio) const = 0;

  /// k(a) = Vmax(a) / Vmax, with its derivatives in a: the force-velocity law at activation a is
  /// g(u / k(a)) (Thelen 2003: 0.25 + 0.75 a). `activation` is the one the contraction dynamics
  /// use (clamped to [activation_floor, 1]). 1 for models whose g does not depend on a.
  virtual CurveJet maxVelocityScale(const MuscleParameters&, double /*activation*/) const { return {1.0, 0.0, 0.0}; }
  /// True when maxVelocityScale is not 1 at every activation.
  virtual bool scalesMaxVelocityWithActivation() const { return false; }
  /// A model whose fibre velocity follows a law of its own instead of the shared balance
  /// a Fmax f g(u / k) + D(u) = A (OpenSim 2.x's Thelen, whose damping and velocity floor enter
  /// every denominator): the shortening velocity from the raw activation, the fibre length and
  /// A = F / cos - Phi_P. The shared laws above then serve planning only (the simulation is not
  /// the plan's model exactly).
  virtual bool hasOwnVelocityLaw() const { return false; }
  /// Throws std::logic_error unless hasOwnVelocityLaw().
  virtual OwnFiberVelocity ownFiberVelocity(const MuscleParameters& p, double activation, double fiber_length_m,
                                            double fiber_force_N) const;

  // ---- Activation dynamics.
  virtual ActivationRate activationRate(const MuscleParameters& p, double excitation, double activation) const = 0;
  virtual ExcitationFromActivation excitationFromActivation(const MuscleParameters& p, double activation,
                                                            double activation_rate_per_s) const = 0;
  virtual ExcitationBoundMargins excitationBoundMargins(const MuscleParameters& p, double activation,
                                                        double activation_rate_per_s) const = 0;
};

/// The model a model file names ("richter_warner", "thelen2003", "degroote_fregly2016",
/// "millard2012": OpenSim's default damped Millard muscle); throws
/// std::invalid_argument listing the known names for any other.
std::shared_ptr<const MuscleModel> muscle_model_named(const std::string& name);
/// The names muscle_model_named accepts.
std::vector<std::string> muscle_model_names();

}  // namespace flatsos::muscles
