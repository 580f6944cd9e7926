#pragma once
// Forward simulation of a MusculoskeletalModel with one of the integrators of stepper.hpp
// (error-controlled; tendon lengths are centimetres, so keep accuracy <= 1e-6), and the
// OpenSim-style state table it reports.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there

#include <string>

#include <Simbody.h>

#include "flatsos/plugin/model/musculoskeletal_model.hpp"
#include "flatsos/plugin/io/state_table.hpp"
#include "flatsos/plugin/integration/stepper.hpp"

namespace flatsos::plugin {

struct SimulationOptions {
  double duration_s = 1.0;
  IntegratorKind integrator = IntegratorKind::RungeKuttaMerson;
  double accuracy = 1e-8;           ///< Simbody integrator accuracy (relative)
  double report_interval_s = 0.01;  ///< rows of the state table
  /// > 0: stop once the integrator has taken this many steps (checked at each report time before
  /// the end; a run that reaches it at the end is complete) and say so. An explicit method where
  /// the muscles' states are stiff (a falling arm's replay, a tendon loaded at tiny activation)
  /// can take millions of tiny steps; 0: no limit.
  long max_steps = 0;
};

struct SimulationResult {
  StoTable states;    ///< make_state_table columns, one row at the start and one per report
  StoTable controls;  ///< make_controls_table columns, the same times
  SimTK::State final_state;
  long integrator_steps = 0;
  IntegratorKind integrator = IntegratorKind::RungeKuttaMerson;  ///< the one used (Automatic resolved)
  bool finite = true;    ///< false: a state became NaN/Inf, integration stopped there
  bool step_limit_reached = false;  ///< true: stopped at SimulationOptions::max_steps
  std::string message;   ///< why it stopped early, empty otherwise
  /// Integrated over the whole duration (no non-finite state, no step limit).
  bool completed() const { return finite && !step_limit_reached; }
};

/// Integrates from `initial` for options.duration_s; never throws for NaN or the step limit: it
/// stops, keeps the rows reported so far, and says so. Throws std::invalid_argument for a
/// non-positive duration, accuracy or report interval, or a negative step limit.
SimulationResult simulate(const MusculoskeletalModel& model, const SimTK::State& initial,
                          const SimulationOptions& options);

/// True when every continuous state (q, u, z) of `s` is finite.
bool all_states_finite(const SimTK::State& s);

}  // namespace flatsos::plugin
