#pragma once
// A Hill-type muscle as a Simbody force element (docs/method/flatness.md, the model).
//
// States (continuous, Simbody z variables): tendon length L_S (m) and activation a (-).
// Input: the neural excitation n, discrete State variables a controller writes: a polynomial
// piece held by value (a constant, or a controller's plan for one period: no allocation) or an
// ExcitationSignal of time (shared, any shape), which takes precedence while set; n is clamped
// to [0, 1] when read.
// Path: the musculotendon length L as a polynomial of joint coordinates (OpenSim's
// MultivariatePolynomialFunction convention, muscles/length_polynomial.hpp); coordinates the
// system does not have are held at fixed values. Moment arms r_i(q) = -dL/dq_i; the tendon force
// F = Phi_S(L_S) acts as the mobility force r_i(q) F on each crossed joint (positive r_i: the
// muscle drives q_i up). Constant moment arms, L(q) = l0 - sum_i d_i q_i, are the order-1 case.
//
// Usage with your own Simbody system (any Pin mobilizers):
//   flatsos::plugin::HillMuscle biceps(forces, params, MusclePath::constantMomentArms(0.43, {{elbow, 0.03}}));
//   ... system.realizeTopology(); State s = system.getDefaultState();
//   biceps.setActivation(s, 0.4); biceps.setTendonLength(s, 0.2347); biceps.setExcitation(s, 0.4);

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there

#include <memory>
#include <vector>

#include <Simbody.h>

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/muscles/length_polynomial.hpp"
#include "flatsos/muscles/muscle_parameters.hpp"
#include "flatsos/plugin/force/excitation_signal.hpp"
#include "flatsos/plugin/model/path_geometry.hpp"

namespace flatsos::plugin {

/// One joint coordinate a muscle crosses: the mobilizer and the muscle's moment arm about it.
struct MomentArm {
  SimTK::MobilizedBody mobilizer;  ///< a mobilizer with one generalized coordinate (Pin)
  double moment_arm_m = 0.0;       ///< d_i; positive: shortening the muscle increases q_i
};

/// One argument of a path's length polynomial: a mobilizer with one generalized coordinate
/// (Pin), or, without a mobilizer, a coordinate held at a fixed value.
struct PathArgument {
  SimTK::MobilizedBody mobilizer;  ///< empty handle: held
  double held_value_rad = 0.0;     ///< used when the mobilizer is empty
};

/// The musculotendon length as a polynomial of its arguments.
struct MusclePath {
  muscles::LengthPolynomial length_m;  ///< dimension = arguments.size()
  std::vector<PathArgument> arguments;
  /// When set, the length and moment arms come from it instead of the polynomial (same
  /// arguments; path_geometry.hpp).
  std::shared_ptr<const PathGeometry> geometry;
  /// L(q) = l0 - sum_i d_i q_i (an order-1 polynomial).
  static MusclePath constantMomentArms(double length_at_zero_angles_m, const std::vector<MomentArm>& moment_arms);
};

class HillMuscleImpl;

class HillMuscle : public SimTK::Force::Custom {
 public:
  /// Validates the parameters (std::invalid_argument names the muscle and the field) and adds
  /// the muscle to `forces`. The defaults of the states are a = 0.05 and a tendon at slack
  /// length; set the real initial states on your State.
  HillMuscle(SimTK::GeneralForceSubsystem& forces, const muscles::MuscleParameters& parameters,
             MusclePath path);
  HillMuscle() = default;

  const muscles::MuscleParameters& getParameters() const;
  const MusclePath& getPath() const;

  // --- states (Stage::Model or later) ---
  double getActivation(const SimTK::State& s) const;
  void setActivation(SimTK::State& s, double activation) const;
  double getTendonLength(const SimTK::State& s) const;
  void setTendonLength(SimTK::State& s, double tendon_length_m) const;

  // --- excitation input ---
  /// Hold a constant excitation (replaces any signal). Throws for NaN.
  void setExcitation(SimTK::State& s, double excitation) const;
  /// Hold a polynomial excitation piece (replaces any signal; allocates nothing). Throws
  /// std::invalid_argument naming the muscle for a piece that fails ExcitationPolynomial::validate.
  void setExcitationPolynomial(SimTK::State& s, const ExcitationPolynomial& piece) const;
  /// Drive the excitation by a signal of time (nullptr: back to the held value).
  void setExcitationSignal(SimTK::State& s, std::shared_ptr<const ExcitationSignal> signal) const;
  /// The whole input (held piece and signal), to set again later, e.g. late by a delay.
  ExcitationInput getExcitationInput(const SimTK::State& s) const;
  void setExcitationInput(SimTK::State& s, const ExcitationInput& input) const;
  /// Excitation in effect at the state's time, clamped to [0, 1].
  double getExcitation(const SimTK::State& s) const;
  /// Same before clamping (to count and report clamps).
  double getUnclampedExcitation(const SimTK::State& s) const;

  // --- outputs ---
  double getMusculotendonLength(const SimTK::State& s) const;          ///< L(q), Stage::Position
  double getMusculotendonLengtheningRate(const SimTK::State& s) const; ///< dL/dt, Stage::Velocity
  double getFiberLength(const SimTK::State& s) const;                  ///< L_M (L - L_S without pennation)
  double getTendonForce(const SimTK::State& s) const;                  ///< Phi_S(L_S), N
  /// u = -dL_M/dt along the fibre, from the contraction dynamics (Stage::Velocity).
  double getFiberShorteningVelocity(const SimTK::State& s) const;
  /// dL_S/dt and da/dt (Stage::Velocity; the excitation is read at the state's time).
  double getTendonLengthDerivative(const SimTK::State& s) const;
  double getActivationDerivative(const SimTK::State& s) const;

  /// r_k = -dL/dx_k about path argument k at the state's posture (0 for a held argument; Stage::Position).
  double getMomentArm(const SimTK::State& s, int argument) const;

  // --- for integrators (Stage::Velocity) ---
  /// Position of L_S in State::getY(); the activation is the next entry.
  int getTendonLengthYIndex(const SimTK::State& s) const;
  /// d(dL_S/dt)/dL_S and d(dL_S/dt)/da at the state's path length: the stiff part of the muscle.
  muscles::TendonLengthDerivativePartials getTendonLengthDerivativePartials(const SimTK::State& s) const;
  /// d(da/dt)/da at the state's excitation.
  double getActivationDerivativePartial(const SimTK::State& s) const;

 private:
  const HillMuscleImpl& impl() const;
};

}  // namespace flatsos::plugin
