#pragma once
// Replays an open-loop plan on the Simbody model from the plan's initial state and measures how
// far the simulation departs from the plan (joint angles, activations, tendon lengths) at the
// reported times.
#include <algorithm>
#include <cmath>

#include "flatsos/planner/motion_planner.hpp"
#include "flatsos/planner/planned_excitation.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"

namespace flatsos::test {

struct OpenLoopReplay {
  plugin::SimulationResult sim;
  double max_q_error_rad = 0.0, max_activation_error = 0.0, max_tendon_length_error_m = 0.0;
  double min_tendon_force_N = 1e300;
};

inline OpenLoopReplay replay_open_loop(const planner::FlatOutputMap& flat, const planner::MuscleState& s0,
                                       const planner::OpenLoopPlan& plan, double accuracy, double report_interval_s) {
  const auto& model = flat.model();
  SimTK::State s = model.defaultState();
  model.setJointAngles(s, s0.q_rad);
  model.setJointSpeeds(s, s0.qd_rad_per_s);
  model.setTendonLengths(s, s0.tendon_length_m);
  model.setActivations(s, s0.activation);
  const auto excitation = planner::PlannedExcitation::create(flat, plan.path, *plan.Y);
  for (int j = 0; j < model.numMuscles(); ++j) model.muscle(j).setExcitationSignal(s, excitation->signal(j));
  plugin::SimulationOptions o;
  o.duration_s = plan.path.duration_s;
  o.accuracy = accuracy;
  o.report_interval_s = report_interval_s;
  OpenLoopReplay out;
  out.sim = plugin::simulate(model, s, o);
  const int n = model.numJoints();
  for (const auto& row : out.sim.states.rows) {
    const double t = row[0];
    const planner::Jet qj = plan.jointJet(t);
    const planner::MusclePoint& mp = excitation->at(t);
    for (int i = 0; i < n; ++i)
      out.max_q_error_rad = std::max(out.max_q_error_rad, std::abs(row[static_cast<std::size_t>(1 + 2 * i)] - qj(i, 0)));
    for (int j = 0; j < model.numMuscles(); ++j) {
      const std::size_t at = static_cast<std::size_t>(1 + 2 * n + 5 * j);
      out.max_activation_error = std::max(out.max_activation_error, std::abs(row[at] - mp.activation[j]));
      out.max_tendon_length_error_m = std::max(out.max_tendon_length_error_m, std::abs(row[at + 1] - mp.tendon_length_m[j]));
      out.min_tendon_force_N = std::min(out.min_tendon_force_N, row[at + 2]);
    }
  }
  return out;
}

}  // namespace flatsos::test
