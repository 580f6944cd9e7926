#pragma once
// Checks of the inputs every planner entry point shares (open-loop plans, RH steps, the
// collocation reference). Each throws std::invalid_argument naming the field.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/joint_paths.hpp"

namespace flatsos::planner::detail {

/// `size` finite values. `what` is a C string: checks that pass build no message (the RH step
/// runs them every period).
void require(const Eigen::VectorXd& v, int size, const char* what);

/// One finite reserve >= 0 N per muscle.
void require_reserves(const Eigen::VectorXd& reserves_N, int muscles);

/// An initial muscle state the flat outputs can start from: one finite tendon length and
/// activation per muscle, activations in (0, 1], taut tendons.
void require_initial_muscle_state(const FlatOutputMap& flat, const MuscleState& initial);

/// A posture where every musculotendon path is longer than its tendon's slack length, as
/// flatness needs taut tendons (failing that, typically degrees were given as radians).
/// Allocates nothing when it passes.
void require_taut_tendons_possible(const plugin::MusculoskeletalModel& model,
                                   const Eigen::VectorXd& q_rad, const char* what);

/// Joint angles inside every joint's range (the model's range_rad, or range_m of a slider; a joint
/// without one is unbounded, and one with a limit torque has a soft stop a task may press into):
/// std::invalid_argument naming the joint, its value and its range in the user's units (degrees
/// for a pin). Allocates nothing when it passes.
void require_within_joint_ranges(const plugin::ModelDescription& model,
                                 const Eigen::VectorXd& q_rad, const char* what);

/// A warning for each joint whose path leaves its range over [0, T] (sampled at `points` times),
/// naming the joint, how far and when; none when it stays inside.
std::vector<std::string> joint_range_warnings(const plugin::ModelDescription& model,
                                              const JointPath& path, double duration_s, int points);

}  // namespace flatsos::planner::detail
