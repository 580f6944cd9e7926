#include "flatsos/planner/sos_program.hpp"
#include "flatsos/planner/sos_program_study.hpp"

#include <stdexcept>

#include "flatsos/plugin/stopwatch.hpp"
#include "sos/effort_exchange.hpp"
#include "sos/sos_bounds.hpp"
#include "sos/sos_exchange.hpp"
#include "sos/sos_setup.hpp"
#include "sos/whole_program_nlp.hpp"

namespace flatsos::planner {

namespace {
void finish(const FlatOutputMap& flat, const detail::SosSetup& setup, const Eigen::VectorXd& theta,
            SosProgramResult& result) {
  result.cost_N_s = setup.effort_cost_constant + setup.effort_cost.dot(theta);
  if (result.effort_name.empty()) {  // the map's linear effort
    result.effort_name = "tendon_force";
    result.effort_value = result.cost_N_s;
    result.effort_unit = flat.effortUnit();
  }
  result.Y = detail::flat_outputs_of(setup, theta);
  result.status = SolveStatus::Solved;
}
}  // namespace

SosProgramMethod sos_program_method(const std::string& name) {
  for (const SosProgramMethod m : {SosProgramMethod::Exchange, SosProgramMethod::WholeProgramNlp})
    if (name == to_string(m)) return m;
  throw std::invalid_argument("SOS program method '" + name + "': expected 'exchange' or 'whole_program_nlp'");
}

namespace {
SosProgramResult solve(const FlatOutputMap& flat, const TorqueModel& torque, double duration_s,
                       const FlatOutputBoundary& boundary, const Eigen::VectorXd& reserves_N,
                       const detail::SosSettings& options, const MusclesAlongPath* muscles,
                       const detail::BoundsWarmStart* warm) {
  const Stopwatch setup_time;
  detail::SosSetup setup = detail::set_up_sos_program(flat, torque, duration_s, boundary, reserves_N, options);
  SosProgramResult result;
  result.method = to_string(options.method);
  result.setup_seconds = setup_time.seconds();

  Eigen::VectorXd theta;
  const bool bounds = muscles && options.bounds.enforce;
  if (options.effort && (!muscles || options.method != SosProgramMethod::Exchange))
    throw std::invalid_argument("SOS program: the effort '" + options.effort->name() +
                                "' needs the muscles along the path and the exchange method");
  if (options.method == SosProgramMethod::WholeProgramNlp) {
    if (!detail::solve_whole_program(setup, options, theta, result)) return result;
    if (bounds) {
      const bool within = detail::check_excitation_bounds(setup, *muscles, options, theta, result);
      result.solve_seconds += result.bounds_seconds;
      if (!within) return result;
    }
    finish(flat, setup, theta, result);
    return result;
  }
  SequentialLpBasis basis;
  const double tolerance_N = bounds ? detail::kLooseConstraintTolerance_N : detail::kConstraintTolerance_N;
  if (!detail::solve_by_exchange(setup, options, theta, result, &basis, tolerance_N)) return result;
  if (bounds) {
    const bool bounded =
        detail::impose_excitation_bounds(setup, *muscles, options, theta, result, std::move(basis), warm);
    result.solve_seconds += result.bounds_seconds;
    if (!bounded) return result;
  }
  if (options.effort) {
    const bool minimized = detail::minimize_effort_by_exchange(setup, *muscles, options, *options.effort, theta, result);
    result.solve_seconds += result.effort_seconds;
    if (!minimized) return result;
  }
  finish(flat, setup, theta, result);
  if (options.certify) detail::certify_near_active_pieces(setup, theta, options, result);
  return result;
}
}  // namespace

SosProgramResult solve_sos_program(const FlatOutputMap& flat, const TorqueModel& torque, double duration_s,
                                   const FlatOutputBoundary& boundary, const Eigen::VectorXd& reserves_N,
                                   const SosProgramOptions& options, const MusclesAlongPath* muscles) {
  return solve_sos_program(flat, torque, duration_s, boundary, reserves_N, options, SosProgramStudyOptions{}, muscles);
}

SosProgramResult solve_sos_program(const FlatOutputMap& flat, const TorqueModel& torque, double duration_s,
                                   const FlatOutputBoundary& boundary, const Eigen::VectorXd& reserves_N,
                                   const SosProgramOptions& options, const SosProgramStudyOptions& study,
                                   const MusclesAlongPath* muscles) {
  return solve(flat, torque, duration_s, boundary, reserves_N, detail::sos_settings(options, study), muscles, nullptr);
}

namespace detail {
SosProgramResult solve_sos_program_from(const FlatOutputMap& flat, const TorqueModel& torque, double duration_s,
                                        const FlatOutputBoundary& boundary, const Eigen::VectorXd& reserves_N,
                                        const SosSettings& options, const MusclesAlongPath& muscles,
                                        const BoundsWarmStart& warm) {
  return solve(flat, torque, duration_s, boundary, reserves_N, options, &muscles, &warm);
}
}  // namespace detail

}  // namespace flatsos::planner
