#include "flatsos/planner/receding_horizon_controller.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "flatsos/plugin/model/plausibility.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "flatness/input_checks.hpp"

namespace flatsos::planner {

namespace {
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

void RecedingHorizonController::observe(const SimTK::State& state, double t) {
  if (!observer_.enabled()) return;
  plant_->system().realize(state, SimTK::Stage::Acceleration);
  for (int i = 0; i < plant_->numJoints(); ++i) qdd_[i] = plant_->joint(i).getOneUDot(state, 0);
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
  options_.planner(flat_, workspace_, q_, qd_, plan_options_, step_);
  if (step_.status != SolveStatus::Solved && !plan_options_.flat_start.empty()) {
    // No plan carries the muscles on from where they are: a free start, as the paper's.
    rec.free_start_message = step_.message;
    plan_options_.flat_start.value.resize(0);
    plan_options_.start_qdd.resize(0);
    options_.planner(flat_, workspace_, q_, qd_, plan_options_, step_);
  }
}

const RecedingHorizonRecord& RecedingHorizonController::step(SimTK::State& state) {
  const Stopwatch wall;
  const double t = state.getTime();
  plant_->jointAngles(state, q_);
  plant_->jointSpeeds(state, qd_);
  observe(state, t);  // before the record is overwritten: it holds the previous period's time

  RecedingHorizonRecord& rec = record_;
  rec.time_s = t;
  rec.status = SolveStatus::Failed;
  rec.message.clear();
  rec.used_previous_plan = false;
  rec.bounds_imposed = false;
  rec.clamped_samples = 0;
  rec.plan_seconds = rec.grid_seconds = rec.slp_seconds = rec.bounds_seconds = rec.effort_seconds = 0.0;
  rec.free_start_message.clear();
  plan_options_.reference_time_s = t;  // a tracked reference's time (unused for a set point)
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
    if (step_.status == SolveStatus::Solved) {
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
  bool have_excitations = false;
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
  if (rec.status != SolveStatus::Solved) ++plan_failures_;
  clamped_samples_ += rec.clamped_samples;
  if (rec.bounds_imposed) ++bounded_steps_;
  ++steps_;
  previous_q_ = q_, previous_qd_ = qd_, previous_qdd_ = qdd_;
  rec.wall_seconds = wall.seconds();
  if (options_.keep_history) history_.push_back(rec);
  return rec;
}

std::vector<plugin::StoTable> prediction_tables(const RecedingHorizonController& controller) {
  const plugin::MusculoskeletalModel& model = controller.plant();
  std::vector<plugin::StoTable> out;
  const auto& history = controller.history();
  for (std::size_t k = 0; k < history.size(); ++k) {
    const PlanInUse& plan = history[k].plan;
    if (plan.empty()) continue;
    plugin::StoTable t;
    t.name = "prediction";
    t.metadata = {{"step", std::to_string(k)}, {"planned_at_s", std::to_string(history[k].time_s)}};
    t.columns = {"time"};
    for (int j = 0; j < model.numJoints(); ++j) {
      t.columns.push_back(plugin::coordinate_value_column(model, j));
      t.columns.push_back(plugin::coordinate_speed_column(model, j));
    }
    for (int i = 0; i <= 10; ++i) {
      const double tau = plan.path.duration_s * i / 10.0;
      const Jet jq = plan.path.jet(tau, 2);
      std::vector<double> row = {plan.start_time_s + tau};
      for (int j = 0; j < model.numJoints(); ++j) row.push_back(jq(j, 0)), row.push_back(jq(j, 1));
      t.rows.push_back(std::move(row));
    }
    out.push_back(std::move(t));
  }
  return out;
}

std::string plan_failures_sentence(const RecedingHorizonController& controller) {
  std::ostringstream why;
  why << controller.planFailures() << " of " << controller.steps() << " plans failed (the previous plan's tail ran instead)";
  const auto& history = controller.history();
  const auto first = std::find_if(history.begin(), history.end(),
                                  [](const RecedingHorizonRecord& r) { return r.status != SolveStatus::Solved; });
  if (first != history.end()) why << ", the first at t = " << first->time_s << " s: " << first->message;
  return why.str();
}

RecedingHorizonRun run_receding_horizon(RecedingHorizonController& controller, const SimTK::State& initial,
                                        const plugin::ClosedLoopOptions& options, double settle_tolerance_rad) {
  detail::require_within_joint_ranges(controller.plant().description(), controller.plant().jointAngles(initial),
                                      "start joint angles (q0)");
  plugin::ClosedLoopOptions o = options;
  o.control_period_s = controller.options().control_period_s;
  RecedingHorizonRun run;
  run.loop = plugin::simulate_closed_loop(controller.plant(), controller, initial, o);
  run.predictions = prediction_tables(controller);
  const Eigen::VectorXd& target = controller.options().plan.target_q_rad;
  if (run.loop.finite)
    run.settling_time_s = plugin::settling_time(controller.plant(), run.loop.states, target, settle_tolerance_rad);
  constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;
  if (!run.loop.finite) run.failures.push_back("the simulation became non-finite");
  if (run.loop.finite && run.settling_time_s < 0.0) {
    const Eigen::VectorXd error = (controller.plant().jointAngles(run.loop.final_state) - target).cwiseAbs();
    double error_rad = 0.0, error_m = 0.0;  // pins', sliders'
    for (int j = 0; j < error.size(); ++j) {
      double& worst = controller.plant().description().joints[static_cast<std::size_t>(j)].isSlider() ? error_m : error_rad;
      worst = std::max(worst, error[j]);
    }
    std::ostringstream why;
    why << "never settled within " << settle_tolerance_rad * kDegPerRad << " deg of the target in " << o.duration_s
        << " s (final error " << error_rad * kDegPerRad << " deg";
    if (error_m > 0.0) why << ", " << error_m << " m along sliders";
    why << ")";
    run.failures.push_back(why.str());
  }
  if (controller.planFailures() > 0) run.failures.push_back(plan_failures_sentence(controller));
  return run;
}

}  // namespace flatsos::planner
