#pragma once
// The inverse problem along a measured motion with the muscles' dynamics (what OpenSim's
// MocoInverse solves): the joint path is the motion itself (its coordinates filtered and splined
// as OpenSim's tools do, plugin::process_coordinates_like_opensim), so flatness gives every
// muscle's force, activation and excitation from the flat outputs Y. The effort (squared
// excitations by default, MocoInverse's) is minimized over Y for the whole motion at once, with
// the reserves and the excitation and activation bounds: the open-loop plan's SOS program and
// sequential QP (docs/method/sos_program.md) along this path, with the muscles' states free at
// both ends.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "flatsos/planner/effort.hpp"
#include "flatsos/planner/open_loop.hpp"
#include "flatsos/plugin/io/motion_processing.hpp"

namespace flatsos::planner {

struct InverseProblemOptions {
  /// What to minimize: null means squared excitations (MocoInverse's default); a linear effort
  /// is the plan's own linear program.
  std::shared_ptr<const Effort> effort;
  /// Minimum tendon force per muscle (N): every tendon stays taut, as the flat outputs need.
  /// Empty: 1 N each.
  Eigen::VectorXd reserves_N;
  /// The flat outputs' basis and the bounds (OpenLoopOptions' defaults: quintic B-splines on
  /// spans chosen from the model; uniform spans, a measured motion has no preferred start).
  SosProgramOptions sos = [] {
    SosProgramOptions s;
    s.flat_output_degree = 5;
    s.flat_output_spans = 0;
    return s;
  }();
};

struct InverseProblemResult {
  SolveStatus status = SolveStatus::Failed;
  std::string message;
  std::vector<double> time_s;        ///< the motion's report times
  Eigen::MatrixXd activation, excitation, tendon_force_N;  ///< frames x muscles
  std::string effort_name, effort_unit;
  double effort_value = 0.0;         ///< the effort over the whole motion
  OpenLoopPlan plan;                 ///< the path (the motion), the flat outputs, the SOS program's report
  double wall_seconds = 0.0;
};

/// The minimum-effort muscle trajectory along `motion` (its columns must include each joint's
/// coordinate by OpenSim's name), from its first report time to its last. Throws
/// std::invalid_argument naming a missing coordinate or a bad option; solver outcomes come back
/// as statuses, with the reason.
InverseProblemResult solve_inverse_problem(const FlatOutputMap& flat, const plugin::ProcessedCoordinates& motion,
                                           const InverseProblemOptions& options = {});

/// The motion as the joint path the inverse problem plans along (t = 0 at its first report time).
JointPath motion_path(const plugin::MusculoskeletalModel& model, const plugin::ProcessedCoordinates& motion);

}  // namespace flatsos::planner
