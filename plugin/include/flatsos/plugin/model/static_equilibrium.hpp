#pragma once
// Initial states at rest for a whole model: every tendon at its static equilibrium
// (muscles::static_equilibrium_tendon_length, the scalar law, also usable on its own).

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <Eigen/Core>
#include <Simbody.h>

#include "flatsos/muscles/static_equilibrium.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace flatsos::plugin {

using muscles::static_equilibrium_tendon_length;

/// Sets every muscle's tendon length to its static equilibrium for the given activations at the
/// state's joint angles, and the activations themselves.
void equilibrate_tendons(const MusculoskeletalModel& model, SimTK::State& s,
                         const Eigen::VectorXd& activations);

}  // namespace flatsos::plugin
