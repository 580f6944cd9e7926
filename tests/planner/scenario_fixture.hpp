#pragma once
// The paper's open-loop scenario (the paper, section 5) on the arm model.
#include <algorithm>
#include <memory>

#include "../plugin/arm_fixture.hpp"
#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/motion_planner.hpp"
#include "flatsos/planner/open_loop_study.hpp"
#include "flatsos/plugin/model/static_equilibrium.hpp"

namespace flatsos::test {

struct ArmPlanning {
  std::shared_ptr<const plugin::MusculoskeletalModel> model = load_arm();
  planner::FlatOutputMap flat{model};
};

/// q0 = [0, 10 deg], qd0 = [0.001, 0.002] rad/s, a0 of the paper, tendons in static equilibrium.
inline planner::MuscleState open_loop_initial_state(const plugin::MusculoskeletalModel& model) {
  planner::MuscleState s;
  s.q_rad = Eigen::Vector2d(0.0, deg(10));
  s.qd_rad_per_s = Eigen::Vector2d(0.001, 0.002);
  s.activation = paper_a0();
  const Eigen::VectorXd L = model.musculotendonLengths(s.q_rad);
  s.tendon_length_m.resize(6);
  for (int j = 0; j < 6; ++j)
    s.tendon_length_m[j] = plugin::static_equilibrium_tendon_length(model.muscle(j).getParameters(), L[j], s.activation[j]);
  return s;
}

inline planner::OpenLoopOptions open_loop_options() {
  planner::OpenLoopOptions o = planner::open_loop_options(planner::Preset::Paper);
  o.duration_s = 3.0;
  o.target_q_rad = Eigen::Vector2d(deg(90), 0.0);
  o.reserves_N = Eigen::VectorXd::Constant(6, 10.0);
  return o;
}

/// The same transfer in T seconds with flat outputs in clamped B-splines of the given degree on
/// `spans` spans (the torque model with at least as many pieces).
inline planner::OpenLoopOptions open_loop_options(double T, int degree = 4, int spans = 1) {
  planner::OpenLoopOptions o = open_loop_options();
  o.duration_s = T;
  o.sos.flat_output_degree = degree;
  o.sos.flat_output_spans = spans;
  o.sos.flat_output_span_growth = 1.0;  // uniform, explicitly: the study code below reads it unresolved
  o.torque.pieces = std::max(12, spans);
  return o;
}

/// The study settings that optimize the joint path by the joint Newton method.
inline planner::OpenLoopStudyOptions joint_newton_study() {
  planner::OpenLoopStudyOptions s;
  s.free_path.method = planner::FreePathMethod::JointNewton;
  return s;
}

/// The transfer with the joint path free (with joint_newton_study): flat outputs and torque
/// pieces on `spans` spans growing by 1.06, the path on 12 spans growing by 1.4. A low-effort
/// transfer throws the arm up in its first few tenths of a second: short spans there.
inline planner::OpenLoopOptions graded_free_path_options(double T, int degree, int spans) {
  planner::OpenLoopOptions o = open_loop_options(T, degree, spans);
  o.sos.flat_output_span_growth = 1.06;
  o.torque.pieces = spans;
  o.torque.piece_growth = 1.06;
  o.free_path.enabled = true;
  o.free_path.spans = 12;
  o.free_path.span_growth = 1.4;
  return o;
}

}  // namespace flatsos::test
