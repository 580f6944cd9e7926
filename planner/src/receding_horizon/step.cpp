#include "flatsos/planner/receding_horizon_step.hpp"
#include "flatsos/planner/receding_horizon_study.hpp"
#include "flatsos/planner/slp_study.hpp"

#include <stdexcept>
#include <string>

#include "flatness/input_checks.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "receding_horizon/period_bounds.hpp"
#include "receding_horizon/step_effort.hpp"

namespace flatsos::planner {

using detail::require;
using detail::require_reserves;
using detail::require_taut_tendons_possible;

Eigen::MatrixXd RecedingHorizonStep::excitations(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                                 double tau0_s, double h_s, int count) const {
  if (status != SolveStatus::Solved) throw std::logic_error("RH step: no excitations: the step was not solved (" + message + ")");
  if (count < 1 || !(h_s > 0.0) || !(tau0_s >= 0.0)) throw std::invalid_argument("RH step excitations: need count >= 1, h > 0 s, tau0 >= 0 s");
  PlanExcitationScratch scratch;
  Eigen::MatrixXd out;
  if (!sample_plan_excitations(flat, workspace, path, alpha(), torque_offset_N_m, tau0_s, h_s, count, scratch, out,
                               nullptr, &flat_start))
    throw std::runtime_error("RH step excitations: not finite (the plan leaves the model's valid domain)");
  return out;
}

void validate(const RecedingHorizonOptions& o, const FlatOutputMap& flat) {
  const int n = flat.numJoints();
  if (!(o.horizon_s > 0.0) || !std::isfinite(o.horizon_s)) throw std::invalid_argument("RH step: horizon must be > 0 s");
  if (o.grid_points < 2) throw std::invalid_argument("RH step: need at least 2 grid points");
  if (o.reference) {
    if (o.reference->numJoints() != n)
      throw std::invalid_argument("RH step: the reference has " + std::to_string(o.reference->numJoints()) +
                                  " joints, the model " + std::to_string(n));
    if (!std::isfinite(o.reference_time_s)) throw std::invalid_argument("RH step: the reference time is not finite");
    if (!(o.tracking_correction_s > 0.0)) throw std::invalid_argument("RH step: the tracking correction time must be > 0 s");
    if (o.start_qdd.size() > 0) {
      require(o.start_qdd, n, "starting joint accelerations");
      require(o.start_qddd, n, "starting joint jerks");
    }
    if (!o.flat_start.empty()) {
      require(o.flat_start.value, flat.numFlatOutputs(), "starting flat outputs");
      require(o.flat_start.rate, flat.numFlatOutputs(), "starting flat output rates");
    }
  } else {
    require(o.target_q_rad, n, "target joint angles");
    require_taut_tendons_possible(flat.model(), o.target_q_rad, "target joint angles");
  }
  require_reserves(o.reserves_N, flat.numMuscles());
  if (o.effort) {
    o.effort->validate(flat.numMuscles());
    if (o.effort->tendonForceWeights())
      throw std::invalid_argument("RH step: effort '" + o.effort->name() +
                                  "' is linear in the tendon forces: give it to the flat output map "
                                  "(FlatOutputMap::withEffort), which prices the SLP with it");
  }
  if (o.torque_offset_N_m.size() > 0) require(o.torque_offset_N_m, n, "torque offset");
  const PeriodExcitationBounds& b = o.excitation_bounds;
  if (b.enforce) {
    if (!(b.period_s > 0.0 && b.period_s <= o.horizon_s))
      throw std::invalid_argument("RH step: excitation_bounds.period_s must be in (0, horizon]");
    if (b.samples < 2) throw std::invalid_argument("RH step: excitation_bounds.samples must be >= 2");
  }
}

namespace {
// Takes the last step's effort optimum as this step's alpha when it meets the reserve rows.
bool start_from_last_optimum(RecedingHorizonStep& step) {
  const Eigen::VectorXd& last = step.buffers.effort_alpha;
  if (last.size() != step.reserve_rows.cols() || !last.allFinite() || last.minCoeff() < 0.0) return false;
  const double scale = 1.0 + step.bound_N.cwiseAbs().maxCoeff();
  if ((step.reserve_rows * last - step.bound_N).minCoeff() < -1e-9 * scale) return false;
  step.slp.alpha = last;
  step.slp.status = SolveStatus::Solved;
  step.slp.message.clear();
  step.slp.used_fallback = false;
  step.slp.iterations = 0;
  step.slp.cost_N = step.buffers.slp.costOf(last);
  step.slp.wall_seconds = 0.0;
  return true;
}

// The SLP over the step's rows, or, for a nonlinear effort whose last optimum meets them, that
// optimum: its sequential QP starts there (the first period's bounds are checked as always).
void solve_slp_of(const RecedingHorizonOptions& o, const RecedingHorizonStudyOptions& study, RecedingHorizonStep& step) {
  if (o.effort && !study.slp_by_ipopt && start_from_last_optimum(step)) return;
  if (study.slp_by_ipopt) solve_slp_by_ipopt(step.reserve_rows, step.bound_N, study.warm_start, step.buffers.slp, step.slp);
  else solve_slp(step.reserve_rows, step.bound_N, o.solver, step.buffers.slp, step.slp);
}

// The first period's bounds and a nonlinear effort's minimum, each timed. The effort's
// sequential QP keeps the bounds itself once it starts near them; the bounds' sequential LP moves
// alpha inside first where it does not.
void bound_and_minimize(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const RecedingHorizonOptions& o,
                        const RecedingHorizonStudyOptions& study, RecedingHorizonStep& step) {
  const Stopwatch effort_time;
  const bool minimized = o.effort && detail::minimize_step_effort(flat, workspace, o, step);
  if (o.effort) step.effort_seconds = effort_time.seconds();
  if (minimized) return;
  const Stopwatch bounds_time;
  detail::impose_period_bounds(flat, workspace, o, study.bound_max_iterations, step);
  step.bounds_seconds = bounds_time.seconds();
  if (!o.effort) return;
  const Stopwatch again;
  detail::minimize_step_effort(flat, workspace, o, step);
  step.effort_seconds += again.seconds();
}
}  // namespace

RecedingHorizonStep plan_receding_horizon_step(const FlatOutputMap& flat, const Eigen::VectorXd& q,
                                               const Eigen::VectorXd& qd, const RecedingHorizonOptions& o) {
  return plan_receding_horizon_step(flat, q, qd, o, RecedingHorizonStudyOptions{});
}

RecedingHorizonStep plan_receding_horizon_step(const FlatOutputMap& flat, const Eigen::VectorXd& q,
                                               const Eigen::VectorXd& qd, const RecedingHorizonOptions& o,
                                               const RecedingHorizonStudyOptions& study) {
  plugin::ModelWorkspace workspace = flat.makeWorkspace();
  RecedingHorizonStep step;
  plan_receding_horizon_step(flat, workspace, q, qd, o, study, step);
  return step;
}

RecedingHorizonStep plan_receding_horizon_step(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                               const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                               const RecedingHorizonOptions& o) {
  RecedingHorizonStep step;
  plan_receding_horizon_step(flat, workspace, q, qd, o, step);
  return step;
}

void plan_receding_horizon_step(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const Eigen::VectorXd& q,
                                const Eigen::VectorXd& qd, const RecedingHorizonOptions& o, RecedingHorizonStep& step) {
  static const RecedingHorizonStudyOptions kProduct;  // constant: no allocation per step
  plan_receding_horizon_step(flat, workspace, q, qd, o, kProduct, step);
}

void plan_receding_horizon_step(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const Eigen::VectorXd& q,
                                const Eigen::VectorXd& qd, const RecedingHorizonOptions& o,
                                const RecedingHorizonStudyOptions& study, RecedingHorizonStep& step) {
  const Stopwatch wall;
  const int n = flat.numJoints();
  validate(o, flat);
  if (study.warm_start) require(*study.warm_start, flat.numFlatOutputs(), "SLP warm start");
  if (study.bound_max_iterations < 1) throw std::invalid_argument("RH step: bound_max_iterations must be >= 1");
  require(q, n, "joint angles");
  require(qd, n, "joint speeds");

  step.status = SolveStatus::Failed;
  step.message.clear();
  step.first_period_sampled = false;
  step.grid_seconds = step.bounds_seconds = step.effort_seconds = 0.0;
  step.bounds_imposed = false;
  step.bound_iterations = step.bound_newton_steps = step.bound_lp_pivots = 0;
  if (o.reference) fit_tracking_path(o.horizon_s, std::min(o.tracking_correction_s, o.horizon_s), q, qd, o.start_qdd, o.start_qddd, o.reference, o.reference_time_s, step.path);
  else fit_rest_cubic(o.horizon_s, q, qd, o.target_q_rad, step.path);
  step.torque_offset_N_m = o.torque_offset_N_m;  // same size every period: no allocation
  step.flat_start = o.flat_start;
  if (!o.reference) step.flat_start.value.resize(0);  // a set point's plan: constant alpha
  const bool blended = !step.flat_start.empty();
  if (blended) step.flat_start.blend_s = std::min(o.tracking_correction_s, o.horizon_s);
  const bool offset = o.torque_offset_N_m.size() > 0;
  step.buffers.joint_jet.resize(n, 3);
  step.buffers.torque_N_m.resize(n);
  step.tau_min.setConstant(n, 1e300);
  step.tau_max.setConstant(n, -1e300);
  // A blended start weights alpha differently at each grid time: rows per grid time, as for
  // posture-dependent moment arms.
  const bool varying = !flat.hasConstantMomentArms() || blended;
  const int m = flat.numMuscles();
  // The paper's cost (sum of the flat outputs) is the SLP's default; other effort weights give
  // the cost c = C_Y^T w of the constant flat outputs.
  const bool flat_output_sum = flat.effortIsFlatOutputSum();
  if (flat_output_sum) step.buffers.slp.cost.resize(0);
  else step.buffers.slp.cost.setZero(flat.numFlatOutputs());
  // A blended start has no rows at t = 0 (the forces there are the muscles' own); its forces
  // move most over the first period, where the grid has no point: rows at the excitation
  // bounds' samples there too, so that no tendon goes slack between the grid's points.
  const PeriodExcitationBounds& first = o.excitation_bounds;
  const int period_rows = blended && first.enforce ? first.samples - 1 : 0;
  if (varying) {
    step.reserve_rows.resize((o.grid_points - (blended ? 1 : 0) + period_rows) * m, flat.numFlatOutputs());
    step.bound_N.resize(step.reserve_rows.rows());
  }
  int row = 0;
  // Rows C(t) alpha >= B(t) at time t of the path, and the effort's flat-output part (C_Y(q)^T w,
  // averaged over the horizon's grid) when `priced`. False when the posture leaves the flat
  // outputs' valid region (the step's message says where).
  auto add_rows = [&](double t, bool priced) {
    Jet& j = step.buffers.joint_jet;
    Eigen::VectorXd& tau = step.buffers.torque_N_m;
    step.path.jetInto(t, j);
    flat.model().inverseDynamics(workspace, j.col(0), j.col(1), j.col(2), tau);
    if (offset) tau -= o.torque_offset_N_m;
    step.tau_min = step.tau_min.cwiseMin(tau);
    step.tau_max = step.tau_max.cwiseMax(tau);
    if (!varying) return true;
    // C(q) along the path: Assumption 1 at each posture, then the rows exact there.
    ForceJetMap map;
    const std::string failure = flat.forceJetMapWhereFlat(j.leftCols(1), map);
    if (!failure.empty()) {
      step.message = "the horizon's joint path leaves the postures where the flat outputs are valid, at t = " +
                     std::to_string(t) + " s " + failure;
      return false;
    }
    // Y(t) = (1 - phi0) alpha + phi0 Y0 + phi1 Y0' (constant alpha without a start).
    double phi0[3] = {0.0, 0.0, 0.0}, phi1[3] = {0.0, 0.0, 0.0};
    if (blended) step.flat_start.blend(t, 0, phi0), step.flat_start.blend(t, 1, phi1);
    if (blended && t <= 0.0) return true;
    step.reserve_rows.middleRows(row, m) = (1.0 - phi0[0]) * map.CY;
    step.bound_N.segment(row, m) = o.reserves_N - map.Ctau * tau;
    if (blended) step.bound_N.segment(row, m).noalias() -= map.CY * (phi0[0] * step.flat_start.value + phi1[0] * step.flat_start.rate);
    row += m;
    if (priced && !flat_output_sum)
      step.buffers.slp.cost.noalias() += (1.0 - phi0[0]) * map.CY.transpose() * flat.effortPricingWeights() / o.grid_points;
    return true;
  };
  bool valid = true;
  for (int i = 0; i < o.grid_points && valid; ++i) valid = add_rows(o.horizon_s * i / (o.grid_points - 1), true);
  for (int k = 1; k <= period_rows && valid; ++k) valid = add_rows(first.period_s * k / (first.samples - 1), false);
  if (!valid) {
    step.wall_seconds = wall.seconds();
    return;
  }
  if (!varying) {
    step.reserve_rows = flat.CY();  // no allocation once sized
    slp_bound_vector(flat.Ctau(), step.tau_min, step.tau_max, o.reserves_N, step.bound_N);
    if (!flat_output_sum) step.buffers.slp.cost.noalias() = flat.CY().transpose() * flat.effortPricingWeights();
  }
  step.grid_seconds = wall.seconds();
  solve_slp_of(o, study, step);
  step.status = step.slp.status;
  step.message = step.slp.message;
  bound_and_minimize(flat, workspace, o, study, step);
  step.wall_seconds = wall.seconds();
}

}  // namespace flatsos::planner
