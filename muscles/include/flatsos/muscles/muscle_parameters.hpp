#pragma once
// Parameters of one Hill-type muscle-tendon unit (docs/method/flatness.md). SI units throughout.

#include <cmath>
#include <memory>
#include <string>

namespace flatsos::muscles {

class MuscleModel;
/// The model of muscles that name none: Richter & Warner's laws (richter_warner_muscle.hpp).
std::shared_ptr<const MuscleModel> default_muscle_model();

struct MuscleParameters {
  std::string name;                        ///< used in every error message
  double max_isometric_force_N = 0.0;      ///< Fmax
  double optimal_fiber_length_m = 0.0;     ///< Lopt
  double tendon_slack_length_m = 0.0;      ///< L_slack
  double tendon_strain_at_max_force = 0.04;  ///< tendon force is Fmax at this strain
  double force_length_width = 0.56;        ///< W of the Gaussian force-length curve
  double max_shortening_velocity_in_optimal_lengths_per_s = 10.0;  ///< Vmax / Lopt
  double hill_constant = 0.25;             ///< Ah (curvature of the concentric branch)
  double max_eccentric_force_ratio = 1.5;  ///< gmax: g(u) -> gmax for u -> -inf
  double activation_time_constant_s = 0.01;    ///< T_act
  double deactivation_time_constant_s = 0.04;  ///< T_deact (> T_act: deactivation is slower)
  /// Lower bound of the activation used in the contraction dynamics (the activation state
  /// itself is not clamped). It keeps the forward model finite where a -> 0. A plan whose
  /// activations go below it is not what the plant executes: the planners keep a >= floor as
  /// one of their excitation and activation bounds. Before they did, planned activations in the
  /// paper's receding-horizon scenario went down to about 1e-3 and a floor of 1e-2 drifted the
  /// closed loop by degrees, hence the default 1e-4; models imported from OpenSim carry its
  /// minimum activation (0.01) instead, which their bounded plans keep.
  double activation_floor = 1e-4;
  /// Pennation angle phi0 at optimal fibre length (rad, in [0, pi/2)). The fibres keep a
  /// constant thickness h = Lopt sin(phi0): at fibre length L_M the angle is asin(h / L_M). 0:
  /// fibres along the tendon (the paper's muscles).
  double pennation_angle_at_optimal_rad = 0.0;
  /// Passive fibre strain e0 at which the passive force reaches Fmax; 0: no passive force (the
  /// paper's muscles). See passive_fiber_force.
  double passive_fiber_strain_at_one_norm_force = 0.0;
  /// Shape k of the passive curve's exponential growth (Thelen's KshapePassive).
  double passive_force_length_shape = 4.0;
  /// Fibre damping beta (OpenSim's fiber_damping): a force -beta Fmax u / Vmax along the fibre at
  /// shortening velocity u, i.e. beta Fmax per maximum lengthening velocity. 0: none (the paper's
  /// muscles, Thelen's); Millard's OpenSim muscle has 0.1 by default.
  double fiber_damping = 0.0;
  /// Steepness b of the tanh that smooths the switch between activation and deactivation time
  /// constants (De Groote et al. 2016; OpenSim's activation_dynamics_smoothing).
  double activation_dynamics_smoothing = 0.1;
  /// The laws this muscle follows (muscle_model.hpp); never null in a validated muscle. Which
  /// fields above a model reads is documented with the model.
  std::shared_ptr<const MuscleModel> model = default_muscle_model();

  /// Vmax in m/s.
  double max_shortening_velocity_m_per_s() const {
    return max_shortening_velocity_in_optimal_lengths_per_s * optimal_fiber_length_m;
  }
  /// h = Lopt sin(phi0), m: the fibres' constant thickness; exactly 0 without pennation, and then
  /// without a call to sin (the laws ask for it at every evaluation).
  double fiber_thickness_m() const {
    return pennation_angle_at_optimal_rad != 0.0 ? optimal_fiber_length_m * std::sin(pennation_angle_at_optimal_rad) : 0.0;
  }
  bool hasPassiveFiberForce() const { return passive_fiber_strain_at_one_norm_force > 0.0; }
  /// beta = T_act / T_deact of the activation dynamics.
  double activation_beta() const {
    return activation_time_constant_s / deactivation_time_constant_s;
  }
};

/// Throws std::invalid_argument naming the muscle and the field when a parameter is
/// non-finite or non-physical (non-positive force, lengths, time constants; floor outside
/// (0, 1); pennation outside [0, pi/2); passive strain < 0; no model), then the model's own
/// checks (MuscleModel::validate).
void validate(const MuscleParameters& p);

}  // namespace flatsos::muscles
