#include "flatsos/planner/rest_state.hpp"

#include <stdexcept>

#include "flatsos/planner/receding_horizon_step.hpp"
#include "flatsos/plugin/model/static_equilibrium.hpp"
#include "flatness/input_checks.hpp"

namespace flatsos::planner {

void set_minimum_effort_rest_state(const FlatOutputMap& flat, SimTK::State& state, const Eigen::VectorXd& q,
                                   const Eigen::VectorXd& reserves) {
  // The start's own checks first: the step below would name its angles the target. (Its range is
  // the task's to check: a measured motion's first frame may lie a little outside.)
  const char* start = "start joint angles (q0)";
  detail::require(q, flat.numJoints(), start);
  detail::require_taut_tendons_possible(flat.model(), q, start);
  RecedingHorizonOptions o;
  o.target_q_rad = q;
  o.reserves_N = reserves;
  // The bounds of the first period keep a in [floor, 1] at rest (n = a there): with passive
  // fibres the reserves alone can ask for less force than a stretched fibre already pulls with.
  plugin::ModelWorkspace workspace = flat.makeWorkspace();
  const RecedingHorizonStep rest = plan_receding_horizon_step(flat, workspace, q, Eigen::VectorXd::Zero(q.size()), o);
  if (rest.status != SolveStatus::Solved) throw std::runtime_error("rest state: the SLP failed: " + rest.message);
  Jet Y = Jet::Zero(rest.alpha().size(), 3);
  Y.col(0) = rest.alpha();
  const MusclePoint mp = flat.inverse(workspace, rest.path.jet(0.0, 5), Y);
  for (std::size_t j = 0; j < mp.domain_violation.size(); ++j)
    if (mp.domain_violation[j].violated())
      throw std::runtime_error("rest state outside the model's valid domain: muscle '" +
                               flat.model().description().muscles[j].parameters.name + "': " +
                               mp.domain_violation[j].describe());
  const auto& model = flat.model();
  model.setJointAngles(state, q);
  model.setJointSpeeds(state, Eigen::VectorXd::Zero(q.size()));
  model.setTendonLengths(state, mp.tendon_length_m);
  model.setActivations(state, mp.activation);
  model.setExcitations(state, mp.activation);
}

SimTK::State start_state(const FlatOutputMap& flat, const Eigen::VectorXd& q_rad, const Eigen::VectorXd& qd_rad_per_s,
                         const std::optional<Eigen::VectorXd>& activations, const Eigen::VectorXd& reserves_N) {
  const plugin::MusculoskeletalModel& model = flat.model();
  detail::require(q_rad, flat.numJoints(), "start joint angles (q0)");
  detail::require_within_joint_ranges(model.description(), q_rad, "start joint angles (q0)");
  SimTK::State s = model.defaultState();
  if (activations) {
    model.setJointAngles(s, q_rad);
    plugin::equilibrate_tendons(model, s, *activations);
    model.setExcitations(s, *activations);
  } else {
    set_minimum_effort_rest_state(flat, s, q_rad, reserves_N);
  }
  model.setJointSpeeds(s, qd_rad_per_s);
  return s;
}

}  // namespace flatsos::planner
