#pragma once
// The inputs of a run (start posture and activations, target, duration, reserves) for any model:
// what the command line gives, else the model file's scenario of that name, else a fallback
// sized from the model (start at 0 deg at the minimum-effort rest, target 30 deg further; a
// slider's coordinates in m, its fallback target 0.05 m further).

#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <Simbody.h>
#include <nlohmann/json.hpp>

#include "flatsos/planner/flat_outputs.hpp"

namespace flatsos::examples {

/// As given on the command line (empty / 0: not given). Angles in degrees, a slider's in m.
struct ScenarioOptions {
  std::vector<double> q0_deg, qd0_deg_per_s, a0, target_deg, reserves_N;
  double duration_s = 0.0;
};

struct ScenarioInputs {
  std::string scenario;                    ///< the model's scenario consulted
  Eigen::VectorXd q0_rad, qd0_rad_per_s, target_q_rad, reserves_N;  ///< reserves: one per muscle
  std::optional<Eigen::VectorXd> activations;  ///< none: the minimum-effort rest state at q0
  double duration_s = 0.0;
  nlohmann::json sources;                  ///< per input: "command line", "model" or "default"
  Eigen::VectorXd shown_per_si;            ///< per joint: deg per rad for a pin, 1 for a slider
  nlohmann::json describe() const;         ///< the inputs in the programs' units, with sources
};

/// Adds --q0-deg, --target-deg, --duration-s, --reserves-N and, with `initial_muscle_state`,
/// --qd0-deg-per-s and --a0; the help names the model scenario they default to.
void add_scenario_options(CLI::App& app, ScenarioOptions& options, const std::string& scenario, bool initial_muscle_state,
                          double fallback_duration_s, double fallback_reserve_N);

/// Throws CLI::ValidationError naming the option for a wrong count or an activation outside (0, 1].
ScenarioInputs resolve_scenario(const plugin::MusculoskeletalModel& model, const std::string& scenario,
                                const ScenarioOptions& given, double fallback_duration_s, double fallback_reserve_N);

/// The flat outputs for the run: over the joint ranges when they serve them, else over the
/// region the run visits (q0 and the target, planner/task_region.hpp), said on stdout.
planner::FlatOutputMap task_flat_outputs(std::shared_ptr<const plugin::MusculoskeletalModel> model,
                                         const ScenarioInputs& inputs, const std::string& program);

/// The start: q0, qd0 and, with activations, tendons in static equilibrium (held excitations
/// equal to the activations); without, the minimum-effort rest state at q0 with the reserves.
SimTK::State initial_state(const planner::FlatOutputMap& flat, const ScenarioInputs& inputs);

}  // namespace flatsos::examples
