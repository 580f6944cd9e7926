#pragma once
// Simbody keeps one force-calculation task per System (GeneralForceSubsystem's calcForcesTask)
// and points it at the State being realized to Stage::Dynamics: two threads realizing States of
// one System that far at once race, and their runs differ silently (measured: two threads
// simulating copies of one arm's State, each unlike a single thread's run). Whoever realizes a
// State of a shared model to Dynamics or beyond holds this lock; simulations of one model from
// several threads then take turns, those of different models run in parallel.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there

#include <mutex>

#include <Simbody.h>

namespace flatsos::plugin::detail {

/// The lock of `system` (one per System, for the life of the process; recursive, so that a
/// report callback inside a locked advance may realize too).
std::unique_lock<std::recursive_mutex> lock_system_dynamics(const SimTK::System& system);

}  // namespace flatsos::plugin::detail
