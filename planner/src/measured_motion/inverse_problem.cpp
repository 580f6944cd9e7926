#include "flatsos/planner/inverse_problem.hpp"

#include <algorithm>
#include <memory>
#include <stdexcept>

#include "flatness/input_checks.hpp"
#include "flatsos/planner/joint_reference.hpp"
#include "flatsos/planner/open_loop_study.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "open_loop/plan_along_path.hpp"

namespace flatsos::planner {

JointPath motion_path(const plugin::MusculoskeletalModel& model, const plugin::ProcessedCoordinates& motion) {
  auto reference = std::make_shared<const JointReference>(JointReference::fromMotion(model, motion));
  JointPath path;
  path.reference = reference;
  path.reference_start_s = reference->startTime_s();
  path.duration_s = reference->endTime_s() - reference->startTime_s();
  path.q.assign(static_cast<std::size_t>(model.numJoints()), Polynomial(Eigen::VectorXd::Zero(1)));
  path.correction_end_s = 0.0;  // no correction: the path is the motion
  return path;
}

namespace {

// The plan's muscles at the motion's report times, from the exact inverse map.
void sample_frames(const FlatOutputMap& flat, const plugin::ProcessedCoordinates& motion, InverseProblemResult& r) {
  const double start = motion.report_times_s.front();
  const auto frames = static_cast<Eigen::Index>(motion.report_times_s.size());
  const int m = flat.numMuscles();
  r.time_s = motion.report_times_s;
  r.activation.resize(frames, m), r.excitation.resize(frames, m), r.tendon_force_N.resize(frames, m);
  plugin::ModelWorkspace workspace = flat.makeWorkspace();
  for (Eigen::Index i = 0; i < frames; ++i) {
    const double t = std::min(motion.report_times_s[static_cast<std::size_t>(i)] - start, r.plan.path.duration_s);
    const MusclePoint mp = flat.inverse(workspace, r.plan.jointJet(t), r.plan.flatOutputJet(t));
    r.activation.row(i) = mp.activation.transpose();
    r.excitation.row(i) = mp.excitation.transpose();
    r.tendon_force_N.row(i) = mp.tendon_force_N.transpose();
  }
}

}  // namespace

InverseProblemResult solve_inverse_problem(const FlatOutputMap& flat, const plugin::ProcessedCoordinates& motion,
                                           const InverseProblemOptions& options) {
  const Stopwatch wall;
  const int m = flat.numMuscles();
  if (motion.report_times_s.size() < 2) throw std::invalid_argument("inverse problem: the motion needs at least 2 frames");
  OpenLoopOptions o;
  o.reserves_N = options.reserves_N.size() ? options.reserves_N : Eigen::VectorXd::Constant(m, 1.0);
  detail::require_reserves(o.reserves_N, m);
  o.sos = options.sos;
  o.sos.flat_output_span_growth = 1.0;
  const std::shared_ptr<const Effort> effort = options.effort ? options.effort : effort_named("excitation_squared");
  effort->validate(m);
  const FlatOutputMap map = effort->tendonForceWeights() ? flat.withEffort(effort) : flat;
  if (!effort->tendonForceWeights()) o.sos.effort = effort;

  InverseProblemResult r;
  r.plan.path = motion_path(flat.model(), motion);
  o.duration_s = r.plan.path.duration_s;
  o = resolve_basis(map, o);
  // The muscles' states are free at both ends: no boundary equalities on Y.
  FlatOutputBoundary free_ends;
  free_ends.initial = Eigen::MatrixXd(map.numFlatOutputs(), 0);
  free_ends.terminal = Eigen::MatrixXd(map.numFlatOutputs(), 0);
  plugin::ModelWorkspace workspace = map.makeWorkspace();
  detail::plan_along_path(map, workspace, free_ends, o, OpenLoopStudyOptions{}, r.plan);
  r.status = r.plan.status;
  r.message = r.plan.message;
  r.effort_name = r.plan.sos.effort_name;
  r.effort_unit = r.plan.sos.effort_unit;
  r.effort_value = r.plan.sos.effort_value;
  if (r.status == SolveStatus::Solved) sample_frames(map, motion, r);
  r.wall_seconds = wall.seconds();
  return r;
}

}  // namespace flatsos::planner
