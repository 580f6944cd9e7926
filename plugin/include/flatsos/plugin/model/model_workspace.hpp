#pragma once
// The scratch a MusculoskeletalModel needs for calculations that go through a Simbody State
// (mass matrix, inverse dynamics): the model stays immutable and shareable, and each thread (or
// controller, or plan) owns its workspace, as Pinocchio splits Model and Data.

#include <Simbody.h>

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
  SimTK::Vector udot_, residual_;
  SimTK::Matrix mass_;
};

}  // namespace flatsos::plugin
