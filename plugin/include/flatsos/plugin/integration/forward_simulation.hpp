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
};

struct SimulationResult {
  StoTable states;    ///< make_state_table columns, one row at the start and one per report
  StoTable controls;  ///< make_controls_table columns, the same times
  SimTK::State final_state;
  long integrator_steps = 0;
  bool finite = true;    ///< false: a state became NaN/Inf, integration stopped there
  std::string message;   ///< why it stopped early, empty otherwise
};

/// Integrates from `initial` for options.duration_s; never throws for NaN: it stops and says so.
/// Throws std::invalid_argument for a non-positive duration, accuracy or report interval.
SimulationResult simulate(const MusculoskeletalModel& model, const SimTK::State& initial,
                          const SimulationOptions& options);

/// True when every continuous state (q, u, z) of `s` is finite.
bool all_states_finite(const SimTK::State& s);

}  // namespace flatsos::plugin
