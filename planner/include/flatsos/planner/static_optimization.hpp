#pragma once
// Static optimization along a measured motion, as OpenSim's StaticOptimization tool solves it:
// at each reported frame, the activations a minimizing sum_j w_j a_j^p (p = 2 by default)
// whose muscle forces a_j G_j produce the joint torques the motion needs,
//   R(q) (a .* G) + r .* x = ID(q, qd, qdd),   0 <= a <= 1,
// with G_j a muscle's force per unit activation at the frame's kinematics and x the controls of
// the reserve actuators (one per joint, optimal torque r, unbounded, in the effort like a
// muscle), when asked for. Torques instead of OpenSim's accelerations: the constraints differ by
// the invertible mass matrix, so the optimum is the same. Each frame is one
// separable_power_program.hpp, solved exactly.
//
// G_j follows the OpenSim version the muscles come from (MuscleStrengthRule):
//   OpenSim2:    the muscle's isometric force at a = 1 with its elastic tendon in equilibrium
//                (passive fibre force included, and so scaled by a), times the generic
//                force-velocity factor 1.8 - 1.8 / (1 + exp((0.04 - v) / 0.18)) of
//                v = cos(phi0) (-dL/dt) / Vmax, OpenSim 2.x's rule (Muscle::calcForceVelocity...
//                in its StaticOptimizationTarget; the tutorial's results for arm26 were made so);
//   RigidTendon: the tendon at its slack length and the fibre's active force only, Fmax f(L_M)
//                g(u) cos(phi) with the fibre's shortening speed u = -cos(phi) dL/dt and the
//                muscle's own curves: OpenSim 4's rule (passive force left out, as there).

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "flatsos/planner/effort.hpp"
#include "flatsos/plugin/io/motion_processing.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace flatsos::planner {

enum class MuscleStrengthRule { OpenSim2, RigidTendon };

struct StaticOptimizationOptions {
  double activation_exponent = 2.0;  ///< p > 1 (OpenSim's activation_exponent)
  Eigen::VectorXd weights;           ///< per muscle, > 0; empty: 1 each
  /// Instead of the two above, an effort of the seam (effort.hpp): a PowerEffort of the
  /// activations or of the tendon stress F / Fmax (= a G / Fmax here), p > 1. Excitation efforts
  /// need the activation dynamics static optimization leaves out, and a linear effort has no
  /// unique optimum: both are refused (std::invalid_argument).
  std::shared_ptr<const Effort> effort;
  /// Empty: OpenSim2 when every muscle is OpenSim 2.x's Thelen model ("thelen2003_opensim2"),
  /// RigidTendon otherwise.
  std::optional<MuscleStrengthRule> strength_rule;
  /// Optimal torque (N m; N on a slider) of one reserve actuator per joint; 0: none, and a frame
  /// the muscles cannot meet fails, naming its joint.
  double reserve_optimal_torque_N_m = 0.0;
};

struct StaticOptimizationResult {
  std::vector<double> time_s;        ///< the frames: the motion's report times
  Eigen::MatrixXd activation;        ///< frames x muscles
  Eigen::MatrixXd tendon_force_N;    ///< frames x muscles: a_j G_j
  Eigen::MatrixXd reserve_torque_N_m;  ///< frames x joints (0 without reserves)
  double reserve_optimal_torque_N_m = 0.0;  ///< the options' (0: no reserves)
  Eigen::VectorXd effort;            ///< per frame, sum w a^p (+ reserves' x^p)
  MuscleStrengthRule strength_rule = MuscleStrengthRule::RigidTendon;
  std::vector<std::string> failures;  ///< one per frame that could not be solved, with its reason
  double wall_seconds = 0.0;
  bool success() const { return failures.empty(); }
};

/// G: each muscle's force per unit activation (N) at q, qd under `rule`. The paths are the
/// muscles' geometry where the model carries it (an .osim imported with geometry paths),
/// their fitted polynomials otherwise; the second form also gives the moment arms used
/// (joints x muscles).
Eigen::VectorXd muscle_strength_N(const plugin::MusculoskeletalModel& model, MuscleStrengthRule rule,
                                  const Eigen::VectorXd& q_rad, const Eigen::VectorXd& qd_rad_per_s);
Eigen::VectorXd muscle_strength_N(const plugin::MusculoskeletalModel& model, MuscleStrengthRule rule,
                                  const Eigen::VectorXd& q_rad, const Eigen::VectorXd& qd_rad_per_s,
                                  Eigen::MatrixXd& moment_arms_m);

/// A measured motion file (an OpenSim coordinates table) processed as OpenSim's tools do
/// (plugin::process_coordinates_like_opensim at `cutoff_hz`), the model's sliders read as
/// translations and every other column as an angle. Throws as reading and processing do.
plugin::ProcessedCoordinates read_motion_for(const plugin::MusculoskeletalModel& model, const std::string& motion_file,
                                             double cutoff_hz = 6.0);

/// Static optimization at every report time of `motion`, whose columns must include each
/// joint's coordinate (OpenSim's name). Throws std::invalid_argument naming a missing
/// coordinate or a bad option; a frame that fails is recorded in `failures` (its row holds the
/// solver's last iterate), never silently.
StaticOptimizationResult static_optimization(const plugin::MusculoskeletalModel& model,
                                             const plugin::ProcessedCoordinates& motion,
                                             const StaticOptimizationOptions& options = {});

/// The result as OpenSim writes it: "<name>_activation" and "<name>_force" tables with a time
/// column and one column per muscle (and reserve, "<coordinate>_reserve").
plugin::StoTable static_optimization_activation_table(const plugin::MusculoskeletalModel& model,
                                                      const StaticOptimizationResult& result);
plugin::StoTable static_optimization_force_table(const plugin::MusculoskeletalModel& model,
                                                 const StaticOptimizationResult& result);

}  // namespace flatsos::planner
