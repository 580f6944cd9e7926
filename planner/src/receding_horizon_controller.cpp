#include "flatsos/planner/receding_horizon_controller.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "flatsos/plugin/stopwatch.hpp"

namespace flatsos::planner {

namespace {
// The plan's joint jet at tau; from its end on the plan rests at its target (the cubic's
// acceleration at T is not zero, a rest's is).
Jet plan_jet(const JointPath& path, double tau, int orders) {
  Jet j = path.jet(std::min(tau, path.duration_s), orders);
  if (tau >= path.duration_s && orders > 1) j.rightCols(orders - 1).setZero();
  return j;
}

Jet constant_jet(const Eigen::VectorXd& alpha) {
  Jet j = Jet::Zero(alpha.size(), 3);
  j.col(0) = alpha;
  return j;
}

const RecedingHorizonControllerOptions& validated(const RecedingHorizonControllerOptions& o, const FlatOutputMap& flat) {
  if (!(o.control_period_s > 0.0) || !std::isfinite(o.control_period_s))
    throw std::invalid_argument("RH controller: control period must be > 0 s");
  if (o.excitation_samples_per_period < 2)
    throw std::invalid_argument("RH controller: need at least 2 excitation samples per period");
  validate(o.plan, flat);
  if (!(o.control_period_s <= o.plan.horizon_s))
    throw std::invalid_argument("RH controller: the control period must not exceed the horizon");
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

RecedingHorizonController::RecedingHorizonController(FlatOutputMap flat, RecedingHorizonControllerOptions o,
                                                     std::shared_ptr<const plugin::MusculoskeletalModel> plant)
    : flat_(std::move(flat)),
      plant_(checked_plant(std::move(plant), flat_)),
      options_(validated(o, flat_)),
      workspace_(flat_.makeWorkspace()),
      observer_(flat_.numJoints(), options_.disturbance_observer_gain_per_s),
      fitter_(options_.excitation_samples_per_period, options_.control_period_s) {}

void RecedingHorizonController::observe(const SimTK::State& state, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                        double t) {
  if (!observer_.enabled() || in_use_.empty() || history_.empty()) return;
  // Prediction error of the plan in use: the joint torque the measured motion needs minus the
  // one the plan predicted for now (what its muscles were asked for).
  plant_->system().realize(state, SimTK::Stage::Acceleration);
  Eigen::VectorXd qdd(plant_->numJoints());
  for (int i = 0; i < plant_->numJoints(); ++i) qdd[i] = plant_->joint(i).getOneUDot(state, 0);
  if (!(q.allFinite() && qd.allFinite() && qdd.allFinite())) return;  // the planner reports the state
  const Jet predicted = plan_jet(in_use_.path, t - in_use_.start_time_s, 3);  // q, qd, qdd
  const Eigen::VectorXd error = flat_.torque(workspace_, q, qd, qdd) -
                                flat_.torque(workspace_, predicted.col(0), predicted.col(1), predicted.col(2));
  observer_.update(error, t - history_.back().time_s);
}

bool RecedingHorizonController::sampleExcitations(const PlanInUse& plan, double t, Eigen::MatrixXd& values) {
  const int ns = fitter_.samples();
  const double h = fitter_.spacing_s();
  const double tau0 = t - plan.start_time_s;
  values.resize(flat_.numMuscles(), ns);
  const auto jets = flat_.torqueJetsOnGrid(
      workspace_, [&](double tau) { return plan_jet(plan.path, tau, 3); }, tau0, h, ns);
  const Jet Y = constant_jet(plan.alpha);
  for (int i = 0; i < ns; ++i) {
    TorqueJet tj = jets[static_cast<std::size_t>(i)];
    // The one place the observer's offset meets the muscles: the torque the plan was made for.
    if (plan.torque_offset_N_m.size()) tj.tau.col(0) -= plan.torque_offset_N_m;  // constant: rates unchanged
    const MusclePoint mp = flat_.inverseFromTorque(plan_jet(plan.path, tau0 + h * i, 5), tj, Y);
    if (!mp.excitation.allFinite()) return false;
    values.col(i) = mp.excitation;
  }
  return true;
}

const RecedingHorizonRecord& RecedingHorizonController::step(SimTK::State& state) {
  const Stopwatch wall;
  RecedingHorizonRecord rec;
  rec.time_s = state.getTime();
  const Eigen::VectorXd q = plant_->jointAngles(state), qd = plant_->jointSpeeds(state);
  observe(state, q, qd, rec.time_s);
  RecedingHorizonOptions plan_options = options_.plan;
  if (observer_.enabled()) plan_options.torque_offset_N_m = rec.observer_offset_N_m = observer_.torqueOffset_N_m();

  PlanInUse candidate;
  try {
    const Stopwatch plan_time;
    const RecedingHorizonStep plan = options_.planner(flat_, workspace_, q, qd, plan_options);
    rec.plan_seconds = plan_time.seconds();
    rec.status = plan.status;
    rec.message = plan.message;
    if (plan.status == SolveStatus::Solved)
      candidate = PlanInUse{plan.alpha(), plan.path, rec.time_s, plan_options.torque_offset_N_m};
  } catch (const std::exception& e) {
    rec.status = SolveStatus::Failed;
    rec.message = e.what();
  }

  Eigen::MatrixXd values;
  bool have_excitations = !candidate.empty() && sampleExcitations(candidate, rec.time_s, values);
  if (have_excitations) {
    in_use_ = std::move(candidate);
  } else {
    if (!candidate.empty()) {
      rec.status = SolveStatus::Failed;
      rec.message = "the plan's excitations are undefined on the first period (left the valid domain)";
    }
    // Recursive feasibility: the previous plan's tail, with its own torque offset, is still a
    // valid plan.
    if (!in_use_.empty()) {
      rec.used_previous_plan = true;
      have_excitations = sampleExcitations(in_use_, rec.time_s, values);
    }
  }
  if (have_excitations) {
    rec.clamped_samples = static_cast<int>(((values.array() < 0.0) || (values.array() > 1.0)).count());
    for (int j = 0; j < plant_->numMuscles(); ++j)
      plant_->muscle(j).setExcitationSignal(state, fitter_.signal(fitter_.fit(values.row(j).transpose()), rec.time_s));
    rec.plan = in_use_;
  }
  // Otherwise no plan ever succeeded: the muscles keep their current inputs, no plan is in use.
  rec.wall_seconds = wall.seconds();
  history_.push_back(std::move(rec));
  return history_.back();
}

int RecedingHorizonController::planFailures() const {
  return static_cast<int>(
      std::count_if(history_.begin(), history_.end(), [](const auto& r) { return r.status != SolveStatus::Solved; }));
}

int RecedingHorizonController::clampedSamples() const {
  int n = 0;
  for (const auto& r : history_) n += r.clamped_samples;
  return n;
}

plugin::StoTable prediction_table(const RecedingHorizonController& controller) {
  const plugin::MusculoskeletalModel& model = controller.plant();
  plugin::StoTable out;
  out.name = "predictions";
  out.columns = {"time", "/controller/step"};
  for (const auto& j : model.description().joints) out.columns.push_back("/jointset/" + j.name + "/q_predicted");
  const auto& history = controller.history();
  for (std::size_t k = 0; k < history.size(); ++k) {
    const PlanInUse& plan = history[k].plan;
    for (int i = 0; i <= 10 && !plan.empty(); ++i) {
      const double tau = plan.path.duration_s * i / 10.0;
      const Jet jq = plan.path.jet(tau, 1);
      std::vector<double> row = {plan.start_time_s + tau, static_cast<double>(k)};
      for (int j = 0; j < model.numJoints(); ++j) row.push_back(jq(j, 0));
      out.rows.push_back(std::move(row));
    }
  }
  return out;
}

RecedingHorizonRun run_receding_horizon(RecedingHorizonController& controller, const SimTK::State& initial,
                                        const plugin::ClosedLoopOptions& options, double settle_tolerance_rad) {
  plugin::ClosedLoopOptions o = options;
  o.control_period_s = controller.options().control_period_s;
  RecedingHorizonRun run;
  run.loop = plugin::simulate_closed_loop(controller.plant(), controller, initial, o);
  run.predictions = prediction_table(controller);
  if (run.loop.finite)
    run.settling_time_s = plugin::settling_time(controller.plant(), run.loop.states, controller.options().plan.target_q_rad,
                                                settle_tolerance_rad);
  return run;
}

}  // namespace flatsos::planner
