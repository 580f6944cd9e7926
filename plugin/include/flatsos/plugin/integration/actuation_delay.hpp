#pragma once
// The muscles' inputs on their way from a controller to the plant, late by a fixed delay (a
// stimulator's or a drive's latency): what the controller sets at t reaches the muscles at
// t + delay, shifted in time so that it runs from then as it would have run from t. Until then
// the inputs already in effect stay. The closed loop (closed_loop.hpp) uses it.

#include <Simbody.h>

#include <limits>
#include <vector>

#include "flatsos/plugin/force/excitation_signal.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"
#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there

namespace flatsos::plugin {

class ActuationDelay {
 public:
  /// Throws std::invalid_argument for a delay that is negative or not finite, or a period that
  /// is not > 0. Storage for every command on its way is sized here.
  ActuationDelay(const MusculoskeletalModel& plant, double delay_s, double control_period_s);

  bool active() const { return delay_s_ > 0.0; }
  /// Before the controller acts on `state`: the inputs in effect, to put back afterwards.
  void keepInputsInEffect(const SimTK::State& state);
  /// After the controller changed `state`'s inputs at its time t: sends them on their way (due
  /// at t + delay) and puts back the inputs kept by keepInputsInEffect.
  void holdBack(SimTK::State& state);
  /// When the next command reaches the muscles (infinity: none on its way).
  double nextDue() const;
  /// Sets on `state` every command due by its time (to 1e-9 s), the latest last.
  void applyDue(SimTK::State& state);

 private:
  struct Command {
    double due_s = 0.0;
    std::vector<ExcitationInput> inputs;  ///< one per muscle
  };
  const MusculoskeletalModel& plant_;
  double delay_s_;
  std::vector<ExcitationInput> in_effect_;
  std::vector<Command> ring_;  ///< commands on their way, oldest at head_
  std::size_t head_ = 0, count_ = 0;
};

}  // namespace flatsos::plugin
