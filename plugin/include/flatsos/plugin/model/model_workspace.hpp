#pragma once
// The scratch a MusculoskeletalModel needs for its calculations (a Simbody State for the mass
// matrix, per-body kinematics for inverse dynamics): the model stays immutable and shareable, and
// each thread (or controller, or plan) owns its workspace, as Pinocchio splits Model and Data.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there

#include <Simbody.h>

#include "flatsos/plugin/model/pin_tree_dynamics.hpp"

namespace flatsos::plugin {

class MusculoskeletalModel;

class ModelWorkspace {
 public:
  /// A workspace for `model` (a copy of its default State: tens of microseconds; make it once).
  explicit ModelWorkspace(const MusculoskeletalModel& model);

 private:
  friend class MusculoskeletalModel;
  const MusculoskeletalModel* model_;  ///< which model it belongs to (checked on use)
  SimTK::State state_;
  SimTK::Matrix mass_;
  PinTreeDynamics::Scratch tree_;
};

}  // namespace flatsos::plugin
