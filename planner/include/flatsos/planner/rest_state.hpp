#pragma once
// Rest states the planner can start from.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <optional>

#include <Eigen/Core>
#include <Simbody.h>

#include "flatsos/planner/flat_outputs.hpp"

namespace flatsos::planner {

/// Minimum-effort static equilibrium at joint angles q: the SLP with the target at q gives the
/// constant flat outputs (moved, when needed, until every activation is in [floor, 1]: a
/// passive fibre may pull harder than a reserve asks); the inverse map at rest gives tendon
/// lengths and activations (u = 0).
/// Sets q, qd = 0, L_S, a and held excitations n = a on `state` (a State of flat.model()).
/// Throws std::runtime_error when the SLP fails or the rest lies outside the valid domain.
void set_minimum_effort_rest_state(const FlatOutputMap& flat, SimTK::State& state, const Eigen::VectorXd& q_rad,
                                   const Eigen::VectorXd& reserves_N);

/// The state a plan or a closed loop starts from (a State of flat.model()): joint angles q and
/// speeds qd with the given activations (held excitations equal) and their tendons in static
/// equilibrium, or, without activations, the minimum-effort rest at q for `reserves_N`. Throws
/// std::invalid_argument naming the joint when q lies outside a joint's range.
SimTK::State start_state(const FlatOutputMap& flat, const Eigen::VectorXd& q_rad, const Eigen::VectorXd& qd_rad_per_s,
                         const std::optional<Eigen::VectorXd>& activations, const Eigen::VectorXd& reserves_N);

}  // namespace flatsos::planner
