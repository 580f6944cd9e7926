#pragma once
// Checks of the inputs every planner entry point shares (open-loop plans, RH steps, the
// collocation reference). Each throws std::invalid_argument naming the field.
#include <Eigen/Core>

#include "flatsos/planner/flat_outputs.hpp"

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
void require_taut_tendons_possible(const plugin::MusculoskeletalModel& model, const Eigen::VectorXd& q_rad,
                                   const char* what);

}  // namespace flatsos::planner::detail
