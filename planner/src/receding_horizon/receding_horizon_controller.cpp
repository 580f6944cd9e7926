#include "flatsos/planner/receding_horizon_controller.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "flatsos/plugin/model/plausibility.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "flatness/input_checks.hpp"

namespace flatsos::planner {

namespace {
// Per joint, the torque (or force) all the model's muscles at their maximum isometric force would
// exert about it at posture q, each on its own side: the scale the observer's offset is read on.
Eigen::VectorXd muscle_capacity(const plugin::MusculoskeletalModel& model, const Eigen::VectorXd& q) {
  const Eigen::MatrixXd R = model.momentArmMatrix(q);
  Eigen::VectorXd capacity = Eigen::VectorXd::Zero(R.rows());
  for (int j = 0; j < model.numMuscles(); ++j)
    capacity += model.muscle(j).getParameters().max_isometric_force_N * R.col(j).cwiseAbs();
  return capacity;
}

// The plan's joint jet at tau into `out` (its column count: the orders); from its end on the plan
// rests at its target (the cubic's acceleration at T is not zero, a rest's is).

// The step's options as the controller plans with them: the excitation bounds on exactly the
// samples it applies.
RecedingHorizonOptions controller_plan_options(const RecedingHorizonControllerOptions& o) {
  RecedingHorizonOptions plan = o.plan;
  plan.excitation_bounds.period_s = o.control_period_s;
  plan.excitation_bounds.samples = o.excitation_samples_per_period;
  return plan;
}

// The integral of sum_j u_j^2 over a period from its uniform samples (rows, spacing h) of the
// excitations as the muscles take them (clamped to [0, 1]): composite Simpson where the intervals
// pair up, the trapezoid otherwise.
double squared_excitation_integral(const Eigen::MatrixXd& samples, double h) {
  const Eigen::Index intervals = samples.rows() - 1;
  const bool simpson = intervals % 2 == 0;
  double sum = 0.0;
  for (Eigen::Index i = 0; i <= intervals; ++i) {
    const double w = (i == 0 || i == intervals) ? 1.0 : simpson ? (i % 2 == 1 ? 4.0 : 2.0) : 2.0;
    sum += w * samples.row(i).cwiseMax(0.0).cwiseMin(1.0).squaredNorm();
  }
  return sum * h / (simpson ? 3.0 : 2.0);
}

void check_setpoints(const RecedingHorizonControllerOptions& o, const FlatOutputMap& flat) {
  if (o.setpoints.empty()) return;
  if (o.plan.reference) throw std::invalid_argument("RH controller: set points and a tracked reference exclude each other");
  double previous = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < o.setpoints.size(); ++i) {
    const Setpoint& s = o.setpoints[i];
    const std::string at = "set point " + std::to_string(i + 1);
    if (!std::isfinite(s.time_s) || !(s.time_s > previous))
      throw std::invalid_argument("RH controller: " + at + ": times must be finite and ascending (got " +
                                  std::to_string(s.time_s) + " s)");
    if (s.target_q_rad.size() != flat.numJoints())
      throw std::invalid_argument("RH controller: " + at + ": needs one angle per joint (" +
                                  std::to_string(flat.numJoints()) + ", got " + std::to_string(s.target_q_rad.size()) + ")");
    if (!s.target_q_rad.allFinite()) throw std::invalid_argument("RH controller: " + at + ": a target joint angle is not finite");
    const std::string what = at + "'s target joint angles";
    detail::require_within_joint_ranges(flat.model().description(), s.target_q_rad, what.c_str());
    previous = s.time_s;
  }
}

const RecedingHorizonControllerOptions& validated(const RecedingHorizonControllerOptions& o, const FlatOutputMap& flat) {
  if (!(o.control_period_s > 0.0) || !std::isfinite(o.control_period_s))
    throw std::invalid_argument("RH controller: control period must be > 0 s");
  if (o.excitation_samples_per_period < 2)
    throw std::invalid_argument("RH controller: need at least 2 excitation samples per period");
  // (A horizon that is not > 0 is named by validate.)
  if (o.plan.horizon_s > 0.0 && !(o.control_period_s <= o.plan.horizon_s))
    throw std::invalid_argument("RH controller: the control period must not exceed the horizon");
  validate(controller_plan_options(o), flat);
  // A set point must lie in the joints' ranges (a step's own target need not: the rest state
  // plans one at a measured motion's first frame, which may lie a little outside).
  if (!o.plan.reference)
    detail::require_within_joint_ranges(flat.model().description(), o.plan.target_q_rad, "target joint angles");
  if (!o.planner) throw std::invalid_argument("RH controller: no planner function");
  if (!(o.quick_arrival_fraction > 0.0 && o.quick_arrival_fraction <= 1.0))
    throw std::invalid_argument("RH controller: quick_arrival_fraction must be in (0, 1] (1: the whole horizon always)");
  check_setpoints(o, flat);
  const DeadlineOptions& d = o.deadline;
  if (!(d.deadline_s >= 0.0) || !std::isfinite(d.deadline_s))
    throw std::invalid_argument("RH controller: the deadline must be finite and >= 0 s (0: none)");
  if (!(d.injected_miss_fraction >= 0.0 && d.injected_miss_fraction <= 1.0))
    throw std::invalid_argument("RH controller: the injected deadline-miss fraction must be in [0, 1]");
  return o;
}

std::shared_ptr<const plugin::MusculoskeletalModel> checked_plant(std::shared_ptr<const plugin::MusculoskeletalModel> plant,
                                                                  const FlatOutputMap& flat) {
  if (!plant) return flat.sharedModel();
  if (plant->numJoints() != flat.numJoints() || plant->numMuscles() != flat.numMuscles())
    throw std::invalid_argument("RH controller: the plant has other joints or muscles than the planner's model");
  return plant;
}
}  // namespace

std::vector<std::string> RecedingHorizonController::warnings() const {
  if (options_.plan.reference) return {};  // no set point
  return plugin::joint_angle_warnings(flat_.model().description(), options_.plan.target_q_rad, "target joint angles");
}

RecedingHorizonController::RecedingHorizonController(FlatOutputMap flat, RecedingHorizonControllerOptions o,
                                                     std::shared_ptr<const plugin::MusculoskeletalModel> plant)
    : flat_(std::move(flat)),
      plant_(checked_plant(std::move(plant), flat_)),
      options_(validated(o, flat_)),
      workspace_(flat_.makeWorkspace()),
      observer_(flat_.numJoints(), options_.disturbance_observer_gain_per_s),
      estimator_(flat_.sharedModel()),
      fitter_(options_.excitation_samples_per_period, options_.control_period_s),
      miss_random_(options_.deadline.seed),
      plan_options_(controller_plan_options(options_)) {
  const int n = flat_.numJoints(), m = flat_.numMuscles();
  for (auto* v : {&q_, &qd_, &qdd_, &measured_torque_, &muscle_torque_, &previous_q_, &previous_qd_, &previous_qdd_}) v->setZero(n);
  excitations_.setZero(fitter_.samples(), m);
  start_joint_jet_.setZero(n, 4);
  start_flat_jet_.setZero(flat_.numFlatOutputs(), 3);
  if (observer_.enabled()) plan_options_.torque_offset_N_m.setZero(n);
}

void RecedingHorizonController::startFromPlanInUse(const SimTK::State& state, double t) {
  if (in_use_.empty()) {
    // The first plan: from the run's known initial muscle states (as the estimator starts), their
    // forces and force rates through the forward map.
    MuscleState muscles;
    muscles.q_rad = q_;
    muscles.qd_rad_per_s = qd_;
    muscles.tendon_length_m = plant_->tendonLengths(state);
    muscles.activation = plant_->activations(state);
    const FlatState start = flat_.forward(workspace_, muscles);
    plan_options_.start_qdd = start.q.col(2);
    if (plan_options_.torque_offset_N_m.size() > 0)
      plan_options_.start_qdd += flat_.model().massMatrix(workspace_, q_).ldlt().solve(plan_options_.torque_offset_N_m);
    plan_options_.start_qddd = start.q.col(3);
    plan_options_.flat_start.value = start.Y.col(0);
    plan_options_.flat_start.rate = start.Y.col(1);
    return;
  }
  const double tau = t - in_use_.start_time_s;
  rest_held_jet(in_use_.path, tau, start_joint_jet_);
  plan_options_.start_qdd = start_joint_jet_.col(2);
  // The plan in use's muscles gave its torque less its offset; the new plan's muscles give the
  // same torque only if its acceleration also carries the change of offset.
  const Eigen::VectorXd& now = plan_options_.torque_offset_N_m;
  const Eigen::VectorXd& then = in_use_.torque_offset_N_m;
  if (now.size() > 0 && then.size() == now.size())
    plan_options_.start_qdd += flat_.model().massMatrix(workspace_, q_).ldlt().solve(now - then);
  plan_options_.start_qddd = start_joint_jet_.col(3);
  in_use_.flat_start.jetInto(in_use_.alpha, tau, start_flat_jet_);
  plan_options_.flat_start.value = start_flat_jet_.col(0);
  plan_options_.flat_start.rate = start_flat_jet_.col(1);
}

const Eigen::VectorXd& RecedingHorizonController::targetAt(double t) const {
  const Eigen::VectorXd* target = &options_.plan.target_q_rad;
  for (const Setpoint& s : options_.setpoints)
    if (s.time_s <= t) target = &s.target_q_rad;
  return *target;
}

void RecedingHorizonController::takeMeasurement(const plugin::JointMeasurement& measured, RecedingHorizonRecord& rec) {
  const int n = plant_->numJoints();
  if (measured.q_rad.size() != n || measured.qd_rad_per_s.size() != n || measured.qdd_rad_per_s2.size() != n)
    throw std::invalid_argument("RH controller: a measurement needs one angle, speed and acceleration per joint");
  if (!measured.allFinite() && steps_ > 0) {  // the last valid one (the first is the run's start)
    rec.measurement_held = true;
    ++faults_.non_finite_measurements;
    return;
  }
  q_ = measured.q_rad, qd_ = measured.qd_rad_per_s, qdd_ = measured.qdd_rad_per_s2;  // same sizes: no allocation
}

bool RecedingHorizonController::missedDeadline(double plan_seconds) {
  const DeadlineOptions& d = options_.deadline;
  bool missed = d.deadline_s > 0.0 && plan_seconds > d.deadline_s;
  if (d.injected_miss_fraction > 0.0) missed = std::uniform_real_distribution<double>(0.0, 1.0)(miss_random_) < d.injected_miss_fraction || missed;
  miss_run_ = missed ? miss_run_ + 1 : 0;
  if (missed) ++faults_.deadline_misses;
  faults_.longest_miss_run = std::max(faults_.longest_miss_run, miss_run_);
  return missed;
}

void RecedingHorizonController::observe(double t) {
  if (!observer_.enabled()) return;
  if (!estimator_.started()) return;
  // The model's muscles under the excitations applied since the previous step, along the
  // measured motion; what the measured motion needs beyond their torque is the disturbance.
  if (!(q_.allFinite() && qd_.allFinite() && qdd_.allFinite())) return;  // the planner reports the state
  if (!estimator_.advance({previous_q_, previous_qd_, previous_qdd_}, {q_, qd_, qdd_}, t)) {
    // Its states held (a muscle's integration failed): go on from here, d unchanged this period.
    estimator_.start(estimator_.tendonLengths_m(), estimator_.activations(), t);
    return;
  }
  flat_.model().inverseDynamics(workspace_, q_, qd_, qdd_, measured_torque_);
  estimator_.muscleTorques(q_, muscle_torque_);
  measured_torque_ -= muscle_torque_;
  observer_.follow(measured_torque_, t - record_.time_s);
}

void RecedingHorizonController::applyExcitations(SimTK::State& state, double t) {
  if (observer_.enabled() && !estimator_.started())  // the run's known initial muscle states
    estimator_.start(plant_->tendonLengths(state), plant_->activations(state), t);
  excitation_squared_integral_ += squared_excitation_integral(excitations_, fitter_.spacing_s());
  for (int j = 0; j < plant_->numMuscles(); ++j) {
    const plugin::ExcitationPolynomial piece = fitter_.fit(excitations_.col(j), t);
    plant_->muscle(j).setExcitationPolynomial(state, piece);
    if (observer_.enabled()) estimator_.setExcitation(j, piece);
  }
}

bool RecedingHorizonController::sampleExcitations(const PlanInUse& plan, double t) {
  return sample_plan_excitations(flat_, workspace_, plan.path, plan.alpha, plan.torque_offset_N_m, t - plan.start_time_s,
                                 fitter_.spacing_s(), fitter_.samples(), excitation_scratch_, excitations_, nullptr,
                                 &plan.flat_start);
}

void RecedingHorizonController::planStep(const SimTK::State& state, double t, RecedingHorizonRecord& rec) {
  if (plan_options_.reference) {
    try {
      startFromPlanInUse(state, t);
      const RecedingHorizonOptions& o = plan_options_;
      if (!(o.start_qdd.allFinite() && o.start_qddd.allFinite() && o.flat_start.value.allFinite() &&
            o.flat_start.rate.allFinite()))
        throw std::runtime_error("the muscles' state gives no finite start");
    } catch (const std::exception& e) {  // the muscles' state refused (not finite): a free start
      rec.free_start_message = e.what();
      plan_options_.flat_start.value.resize(0);
      plan_options_.start_qdd.resize(0);
    }
  }
  if (!plan_options_.reference) return planSetpointStep();
  options_.planner(flat_, workspace_, q_, qd_, plan_options_, step_);
  if (step_.status != SolveStatus::Solved && !plan_options_.flat_start.empty()) {
    // No plan carries the muscles on from where they are: a free start, as the paper's.
    rec.free_start_message = step_.message;
    plan_options_.flat_start.value.resize(0);
    plan_options_.start_qdd.resize(0);
    options_.planner(flat_, workspace_, q_, qd_, plan_options_, step_);
  }
}

void RecedingHorizonController::planSetpointStep() {
  const double horizon_s = plan_options_.horizon_s;
  const double quick_s = std::max(options_.quick_arrival_fraction * horizon_s, options_.control_period_s);
  const Eigen::VectorXd& target = plan_options_.target_q_rad;
  const double largest_error = (q_ - target).cwiseAbs().maxCoeff();
  if (quick_target_.size() != target.size() || quick_target_ != target) {
    // A new set point: its first half is too fast a transfer for the quick arrival (where a
    // failed attempt costs several times a step), its second half may be.
    quick_target_ = target;
    quick_retry_below_rad_ = 0.5 * largest_error;
    joint_capacity_N_m_ = muscle_capacity(flat_.model(), target);
  }
  if (quick_s < horizon_s && largest_error < quick_retry_below_rad_ && modelExplainsTheMotion()) {
    plan_options_.horizon_s = quick_s;
    try {
      options_.planner(flat_, workspace_, q_, qd_, plan_options_, step_);
    } catch (...) {  // the next steps plan over the whole horizon again
      plan_options_.horizon_s = horizon_s;
      throw;
    }
    plan_options_.horizon_s = horizon_s;
    if (step_.status == SolveStatus::Solved) return;
    quick_retry_below_rad_ = 0.5 * largest_error;
  }
  options_.planner(flat_, workspace_, q_, qd_, plan_options_, step_);
}

bool RecedingHorizonController::modelExplainsTheMotion() const {
  if (!observer_.enabled()) return false;  // no evidence either way: the whole horizon
  const Eigen::VectorXd& missed = plan_options_.torque_offset_N_m;
  return (missed.cwiseAbs().array() <= kTrustedOffsetOfCapacity * joint_capacity_N_m_.array()).all();
}

void RecedingHorizonController::countStep(const RecedingHorizonRecord& rec, bool have_excitations, bool plan_not_finite) {
  if (rec.status != SolveStatus::Solved && ++plan_failures_ == 1) {  // allocates once, at the first failure
    first_failure_time_s_ = rec.time_s;
    first_failure_message_ = rec.message;
  }
  if (rec.status != SolveStatus::Solved && !plan_not_finite) ++faults_.solver_failures;
  if (rec.used_previous_plan) ++faults_.fallbacks;
  if (!have_excitations) ++faults_.steps_without_plan;
  clamped_samples_ += rec.clamped_samples;
  if (rec.bounds_imposed) ++bounded_steps_;
  ++steps_;
}

const RecedingHorizonRecord& RecedingHorizonController::step(SimTK::State& state) {
  plugin::measure_joints(*plant_, state, exact_);
  return step(state, exact_);
}

const RecedingHorizonRecord& RecedingHorizonController::step(SimTK::State& state, const plugin::JointMeasurement& measured) {
  const Stopwatch wall;
  const double t = state.getTime();
  RecedingHorizonRecord& rec = record_;
  rec.measurement_held = false;
  takeMeasurement(measured, rec);
  observe(t);  // before the record's time is overwritten: it holds the previous period's

  rec.time_s = t;
  rec.status = SolveStatus::Failed;
  rec.message.clear();
  rec.used_previous_plan = false;
  rec.deadline_missed = false;
  rec.bounds_imposed = false;
  rec.clamped_samples = 0;
  rec.plan_seconds = rec.grid_seconds = rec.slp_seconds = rec.bounds_seconds = rec.effort_seconds = 0.0;
  rec.free_start_message.clear();
  plan_options_.reference_time_s = t;  // a tracked reference's time (unused for a set point)
  if (!options_.setpoints.empty()) plan_options_.target_q_rad = targetAt(t);  // same size: no allocation
  if (observer_.enabled()) {
    plan_options_.torque_offset_N_m = observer_.torqueOffset_N_m();
    rec.observer_offset_N_m = plan_options_.torque_offset_N_m;
  } else {
    rec.observer_offset_N_m.resize(0);  // no observer, no estimate (options.plan's offset, if any, stays)
  }

  bool have_candidate = false;
  try {
    const Stopwatch plan_time;
    planStep(state, t, rec);
    rec.plan_seconds = plan_time.seconds();
    rec.grid_seconds = step_.grid_seconds;
    rec.slp_seconds = step_.slp.wall_seconds;
    rec.bounds_seconds = step_.bounds_seconds;
    rec.effort_seconds = step_.effort_seconds;
    rec.status = step_.status;
    rec.message = step_.message;
    rec.bounds_imposed = step_.bounds_imposed;
    rec.deadline_missed = missedDeadline(rec.plan_seconds);  // too late: the previous plan's tail runs
    if (step_.status == SolveStatus::Solved && !rec.deadline_missed) {
      candidate_.alpha = step_.alpha();
      candidate_.path = step_.path;
      candidate_.start_time_s = t;
      candidate_.torque_offset_N_m = plan_options_.torque_offset_N_m;
      candidate_.flat_start = step_.flat_start;
      have_candidate = true;
    }
  } catch (const std::exception& e) {
    rec.status = SolveStatus::Failed;
    rec.message = e.what();
  }

  // A bounded step has sampled exactly these excitations already (same samples, see
  // controller_plan_options).
  bool have_excitations = false, plan_not_finite = false;
  if (have_candidate && step_.first_period_sampled && step_.buffers.excitations.rows() == fitter_.samples()) {
    excitations_ = step_.buffers.excitations;  // same size every period: no allocation
    have_excitations = true;
  } else if (have_candidate) {
    have_excitations = sampleExcitations(candidate_, t);
  }
  if (have_excitations) {
    in_use_ = candidate_;  // same sizes after the first period: copies into in_use_'s storage
  } else {
    if (have_candidate) {
      rec.status = SolveStatus::Failed;
      rec.message = "the plan's excitations are undefined on the first period (left the valid domain)";
      ++faults_.non_finite_plans;
      plan_not_finite = true;
    }
    // Recursive feasibility: the previous plan's tail, with its own torque offset, is still a
    // valid plan.
    if (!in_use_.empty()) {
      rec.used_previous_plan = true;
      have_excitations = sampleExcitations(in_use_, t);
    }
  }
  if (have_excitations) {
    rec.clamped_samples = static_cast<int>(((excitations_.array() < 0.0) || (excitations_.array() > 1.0)).count());
    applyExcitations(state, t);
    rec.plan = in_use_;  // same sizes every period: copies into the record's storage
  } else {
    rec.plan.alpha.resize(0);  // no plan in use: the muscles keep their current inputs
  }
  countStep(rec, have_excitations, plan_not_finite);
  previous_q_ = q_, previous_qd_ = qd_, previous_qdd_ = qdd_;
  rec.wall_seconds = wall.seconds();
  worst_step_s_ = std::max(worst_step_s_, rec.wall_seconds);
  step_times_.add(rec.wall_seconds);
  if (options_.keep_history) history_.push_back(rec);
  return rec;
}

}  // namespace flatsos::planner
