#include "flatsos/planner/receding_horizon.hpp"

#include <chrono>
#include <algorithm>
#include <cmath>

#include <Eigen/Dense>
#include <memory>
#include <stdexcept>

#include "flatsos/plugin/force/excitation_signal.hpp"

namespace flatsos::planner {

namespace {
using Clock = std::chrono::steady_clock;

// Degree of the least-squares polynomial through the excitation samples of one period: n(t) is
// smooth there (a cubic path, constant Y), so degree 6 reproduces it to ~1e-6 (measured).
constexpr int kExcitationFitDegree = 6;

// n(t) = p((t - t0) / duration), held at the ends.
class PolynomialSignal final : public plugin::ExcitationSignal {
 public:
  PolynomialSignal(Polynomial p, double t0, double duration) : p_(std::move(p)), t0_(t0), duration_(duration) {}
  double value(double t) const override { return p_(std::clamp((t - t0_) / duration_, 0.0, 1.0)); }

 private:
  Polynomial p_;
  double t0_, duration_;
};
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

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
}  // namespace

RecedingHorizonController::RecedingHorizonController(const FlatOutputMap& flat, RecedingHorizonControllerOptions o)
    : flat_(flat), options_(std::move(o)) {
  if (!(options_.control_period_s > 0.0) || !std::isfinite(options_.control_period_s))
    throw std::invalid_argument("RH controller: control period must be > 0 s");
  if (options_.excitation_samples_per_period < 2)
    throw std::invalid_argument("RH controller: need at least 2 excitation samples per period");
  if (!(options_.control_period_s <= options_.plan.horizon_s))
    throw std::invalid_argument("RH controller: the control period must not exceed the horizon");
  if (!(options_.disturbance_observer_gain >= 0.0) || !std::isfinite(options_.disturbance_observer_gain))
    throw std::invalid_argument("RH controller: the disturbance observer gain must be a finite number >= 0");
}

const RecedingHorizonRecord& RecedingHorizonController::step(SimTK::State& state) { return step(flat_.model(), state); }

const RecedingHorizonRecord& RecedingHorizonController::step(const plugin::MusculoskeletalModel& model, SimTK::State& state) {
  const auto t0 = Clock::now();
  if (model.numJoints() != flat_.numJoints() || model.numMuscles() != flat_.numMuscles())
    throw std::invalid_argument("RH controller: the plant has other joints or muscles than the planner's model");
  RecedingHorizonRecord rec;
  rec.time_s = state.getTime();
  const Eigen::VectorXd q = model.jointAngles(state), qd = model.jointSpeeds(state);
  RecedingHorizonOptions plan_options = options_.plan;
  if (options_.disturbance_observer_gain > 0.0) {
    if (torque_offset_.size() != flat_.numJoints()) torque_offset_ = Eigen::VectorXd::Zero(flat_.numJoints());
    // Prediction error of the plan in use: the joint torque that the measured motion needs minus
    // the one the plan predicted for now. The plan's muscles were asked for exactly the latter,
    // so the difference is what the plant did not deliver, whatever the cause (tendon, muscle
    // strength, moment arms, masses, external torque). Integrating it makes the offset free: a
    // rest away from the target leaves the plan asking for acceleration the arm does not show.
    const RecedingHorizonRecord* in_use = nullptr;
    for (auto it = history_.rbegin(); it != history_.rend() && !in_use; ++it)
      if (it->alpha.size()) in_use = &*it;
    if (in_use) {
      model.system().realize(state, SimTK::Stage::Acceleration);
      Eigen::VectorXd qdd(model.numJoints());
      for (int i = 0; i < model.numJoints(); ++i) qdd[i] = model.joint(i).getOneUDot(state, 0);
      const Jet predicted = plan_jet(in_use->path, rec.time_s - in_use->plan_start_time_s, 3);  // q, qd, qdd
      // A non-finite measurement leaves the estimate as it is (the planner then reports the state).
      if (q.allFinite() && qd.allFinite() && qdd.allFinite())
        torque_offset_ += options_.disturbance_observer_gain *
                          (flat_.torque(q, qd, qdd) - flat_.torque(predicted.col(0), predicted.col(1), predicted.col(2)));
    }
    plan_options.torque_offset_N_m = torque_offset_;
    rec.torque_offset_N_m = torque_offset_;
  }
  try {
    const RecedingHorizonStep plan = options_.planner(flat_, q, qd, plan_options);
    rec.plan_seconds = plan.seconds;
    rec.status = plan.status;
    rec.message = plan.message;
    if (plan.status == SolveStatus::Solved) {
      rec.alpha = plan.alpha();
      rec.path = plan.path;
      rec.plan_start_time_s = rec.time_s;
    }
  } catch (const std::exception& e) {
    rec.status = SolveStatus::Failed;
    rec.message = e.what();
  }

  // Excitations of the first period from the exact inverse map of the plan in use, sampled on a
  // uniform grid (torque jets share their inverse-dynamics calls) and fitted by one smooth
  // polynomial per muscle: no kinks inside the period for the integrator to resolve.
  const int ns = options_.excitation_samples_per_period;
  const double h = options_.control_period_s / (ns - 1);
  auto sample = [&](Eigen::MatrixXd& values) {
    values.resize(model.numMuscles(), ns);
    const JointPath& path = rec.path;
    const double tau0 = rec.time_s - rec.plan_start_time_s;
    auto jet_at = [&](double tau) { return plan_jet(path, tau, 5); };
    const auto jets = flat_.torqueJetsOnGrid([&](double tau) { return jet_at(tau).leftCols(3).eval(); }, tau0, h, ns);
    for (int i = 0; i < ns; ++i) {
      TorqueJet tj = jets[static_cast<std::size_t>(i)];
      if (rec.torque_offset_N_m.size()) tj.tau.col(0) -= rec.torque_offset_N_m;  // constant: rates unchanged
      const MusclePoint mp = flat_.inverseFromTorque(jet_at(tau0 + h * i), tj, constant_jet(rec.alpha));
      if (!mp.excitation.allFinite()) return false;
      values.col(i) = mp.excitation;
    }
    rec.clamped_samples = static_cast<int>(((values.array() < 0.0) || (values.array() > 1.0)).count());
    return true;
  };
  Eigen::MatrixXd values;
  bool have_excitations = rec.status == SolveStatus::Solved && sample(values);
  if (!have_excitations) {
    if (rec.status == SolveStatus::Solved) {
      rec.status = SolveStatus::Failed;
      rec.message = "the plan's excitations are undefined on the first period (left the valid domain)";
    }
    // Recursive feasibility: the previous plan's tail is still a valid plan.
    for (auto it = history_.rbegin(); it != history_.rend(); ++it)
      if (it->alpha.size()) {
        rec.used_previous_plan = true;
        rec.alpha = it->alpha;
        rec.path = it->path;
        rec.plan_start_time_s = it->plan_start_time_s;
        have_excitations = sample(values);
        break;
      }
  }
  if (have_excitations) {
    const int degree = std::min(ns - 1, kExcitationFitDegree);
    Eigen::MatrixXd V(ns, degree + 1);
    for (int i = 0; i < ns; ++i)
      for (int k = 0; k <= degree; ++k) V(i, k) = std::pow(static_cast<double>(i) / (ns - 1), k);
    const auto qr = V.colPivHouseholderQr();
    for (int j = 0; j < model.numMuscles(); ++j) {
      const Polynomial fit(qr.solve(values.row(j).transpose()));
      model.muscle(j).setExcitationSignal(
          state, std::make_shared<PolynomialSignal>(fit, rec.time_s, options_.control_period_s));
    }
  } else {
    // No plan ever succeeded: the muscles keep their current inputs, and no plan is in use.
    rec.alpha.resize(0);
    rec.path = JointPath{};
  }
  rec.step_seconds = seconds_since(t0);
  history_.push_back(std::move(rec));
  return history_.back();
}

int RecedingHorizonController::planFailures() const {
  int n = 0;
  for (const auto& r : history_) n += r.status != SolveStatus::Solved;
  return n;
}

int RecedingHorizonController::clampedSamples() const {
  int n = 0;
  for (const auto& r : history_) n += r.clamped_samples;
  return n;
}

ClosedLoopResult simulate_closed_loop(RecedingHorizonController& controller, const SimTK::State& initial,
                                      double duration, double accuracy, int reports, double settle_tol,
                                      plugin::IntegratorKind kind) {
  return simulate_closed_loop(controller, controller.flat().model(), initial, duration, accuracy, reports, settle_tol, kind);
}

ClosedLoopResult simulate_closed_loop(RecedingHorizonController& controller, const plugin::MusculoskeletalModel& model,
                                      const SimTK::State& initial, double duration, double accuracy, int reports,
                                      double settle_tol, plugin::IntegratorKind kind) {
  if (!(duration > 0.0) || !std::isfinite(duration)) throw std::invalid_argument("closed loop: duration must be > 0 s");
  if (reports < 1) throw std::invalid_argument("closed loop: need at least one report per period");
  const int n = model.numJoints();
  const double period = controller.options().control_period_s;
  ClosedLoopResult out;
  out.states = plugin::make_state_table(model, "simulation");
  out.predictions.name = "predictions";
  out.predictions.columns = {"time", "/controller/step"};
  for (const auto& j : model.description().joints) out.predictions.columns.push_back("/jointset/" + j.name + "/q_predicted");

  const auto wall0 = Clock::now();
  const auto stepper = plugin::make_stepper(model, kind, accuracy);
  stepper->initialize(initial);
  plugin::append_state_row(model, stepper->state(), out.states);
  const auto append_row = [&](const SimTK::State& st) { plugin::append_state_row(model, st, out.states); };
  std::vector<double> report_times(static_cast<std::size_t>(reports));
  const int steps = static_cast<int>(std::ceil(duration / period - 1e-9));
  for (int k = 0; k < steps && out.finite; ++k) {
    // The controller changes the inputs of the integrator's own state (no copy); Simbody's
    // integrators then restart (CPodes BDF cold), the Rosenbrock method keeps its step size.
    SimTK::State& s = stepper->updState();
    const RecedingHorizonRecord& rec = controller.step(model, s);
    stepper->inputsChanged();
    for (int i = 0; i <= 10 && rec.alpha.size(); ++i) {
      const double tau = rec.path.duration_s * i / 10.0;
      const Jet jq = rec.path.jet(tau, 1);
      std::vector<double> row = {rec.plan_start_time_s + tau, static_cast<double>(k)};
      for (int j = 0; j < n; ++j) row.push_back(jq(j, 0));
      out.predictions.rows.push_back(std::move(row));
    }
    const double t_begin = stepper->state().getTime(), t_end = initial.getTime() + std::min(duration, (k + 1) * period);
    for (int r = 1; r <= reports; ++r) report_times[static_cast<std::size_t>(r - 1)] = t_begin + (t_end - t_begin) * r / reports;
    report_times.back() = t_end;
    out.finite = stepper->advanceTo(t_end, report_times, append_row);
  }
  out.integrator_steps = stepper->stepsTaken();
  out.integrator_attempts = stepper->stepsAttempted();
  out.final_state = stepper->state();
  const SimTK::State& s = out.final_state;
  out.wall_seconds = std::max(seconds_since(wall0), 1e-9);
  out.real_time_factor = (s.getTime() - initial.getTime()) / out.wall_seconds;
  const Eigen::VectorXd& target = controller.options().plan.target_q_rad;
  for (std::size_t r = out.states.rows.size(); r-- > 0;) {
    bool inside = true;
    for (int j = 0; j < n; ++j) inside = inside && std::abs(out.states.rows[r][static_cast<std::size_t>(1 + 2 * j)] - target[j]) <= settle_tol;
    if (!inside) break;
    out.settling_time_s = out.states.rows[r][0];
  }
  if (!out.finite) out.settling_time_s = -1.0;
  return out;
}

void set_minimum_effort_rest_state(const FlatOutputMap& flat, SimTK::State& state, const Eigen::VectorXd& q,
                                   const Eigen::VectorXd& reserves) {
  RecedingHorizonOptions o;
  o.target_q_rad = q;
  o.reserves_N = reserves;
  const RecedingHorizonStep rest = plan_receding_horizon_step(flat, q, Eigen::VectorXd::Zero(q.size()), o);
  if (rest.status != SolveStatus::Solved) throw std::runtime_error("rest state: the SLP failed: " + rest.message);
  const MusclePoint mp = flat.inverse(rest.path.jet(0.0, 5), constant_jet(rest.alpha()));
  if (!mp.inDomain())
    for (const auto& why : mp.domain_violation)
      if (!why.empty()) throw std::runtime_error("rest state outside the model's valid domain: " + why);
  const auto& model = flat.model();
  model.setJointAngles(state, q);
  model.setJointSpeeds(state, Eigen::VectorXd::Zero(q.size()));
  model.setTendonLengths(state, mp.tendon_length_m);
  model.setActivations(state, mp.activation);
  model.setExcitations(state, mp.activation);
}

}  // namespace flatsos::planner
