#include "flatsos/plugin/integration/muscle_rosenbrock_integrator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "system_dynamics_lock.hpp"

namespace flatsos::plugin {

namespace {
// ROS34PW2 (Rang & Angermann 2005, Table 4.3): stage abscissae alpha_ij, Jacobian couplings
// gamma_ij (gamma on the diagonal), weights b (order 3) and b_hat (embedded order 2).
constexpr double kGamma = 4.3586652150845900e-01;
constexpr double kAlpha[4][4] = {{0, 0, 0, 0},
                                 {8.7173304301691801e-01, 0, 0, 0},
                                 {8.4457060015369423e-01, -1.1299064236484185e-01, 0, 0},
                                 {0, 0, 1, 0}};
constexpr double kGammaOff[4][4] = {{0, 0, 0, 0},
                                    {-8.7173304301691801e-01, 0, 0, 0},
                                    {-9.0338057013044082e-01, 5.4180672388095326e-02, 0, 0},
                                    {2.4212380706095346e-01, -1.2232505839045147e+00, 5.4526025533510214e-01, 0}};
constexpr double kB[4] = {2.4212380706095346e-01, -1.2232505839045147e+00, 1.5452602553351020e+00,
                          4.3586652150845900e-01};
constexpr double kBHat[4] = {3.7810903145819369e-01, -9.6042292212423178e-02, 5.0000000000000000e-01,
                             2.1793326075422950e-01};
// Continuous extension (Rang & Angermann; as tabulated in PETSc's TSROSWRA34PW2): the solution
// at t + theta h is y + sum_i b_i(theta) k_i, b_i(theta) = sum_j kDense[i][j] theta^(j+1), and
// b_i(1) = kB[i].
constexpr double kDense[4][3] = {{1.0564298455794094, -1.3864882699759573, 0.5721822314575016},
                                 {2.296429974281067, -8.262611700275677, 4.742931142090097},
                                 {-1.307599564525376, 7.250979895056055, -4.398120075195578},
                                 {-1.045260255335102, 2.398120075195581, -0.9169932983520199}};
constexpr int kOrderEmbedded = 2;  // error ~ h^(kOrderEmbedded + 1)
constexpr double kSafety = 0.9;
constexpr double kMaxGrowth = 5.0, kMaxShrink = 0.2;
constexpr double kMinStep = 1e-12;   // s: below this the integrator gives up
constexpr double kFirstStep = 1e-4;  // s: the first trial step
// A muscle block of W = I - gamma h J with a diagonal below this is a step far beyond an
// unstable time scale of the muscle (J > 0 on the descending limb): the step is rejected.
constexpr double kMinPivot = 0.5;

bool finite(const SimTK::Vector& v) {
  for (int i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}
}  // namespace

MuscleRosenbrockIntegrator::MuscleRosenbrockIntegrator(const SimTK::System& system, const std::vector<HillMuscle>& muscles,
                                                       double accuracy)
    : system_(system),
      multibody_(SimTK::MultibodySystem::isInstanceOf(system) ? &SimTK::MultibodySystem::downcast(system) : nullptr),
      accuracy_(accuracy) {
  if (!(accuracy > 0.0 && accuracy < 1.0)) throw std::invalid_argument("integrator accuracy must be in (0, 1)");
  const auto lock = detail::lock_system_dynamics(system_);
  for (const auto& m : muscles) {
    MuscleSlot slot;
    slot.muscle = m;
    const auto& p = slot.muscle.getParameters();
    slot.stretch_scale_m = p.tendon_strain_at_max_force * p.tendon_slack_length_m;
    slots_.push_back(std::move(slot));
  }
  j_ll_.assign(slots_.size(), 0.0);
  j_la_.assign(slots_.size(), 0.0);
  j_aa_.assign(slots_.size(), 0.0);
  j_lpath_.assign(slots_.size(), 0.0);
}

MuscleRosenbrockIntegrator::~MuscleRosenbrockIntegrator() {
  const auto lock = detail::lock_system_dynamics(system_);
  slots_.clear();
}

void MuscleRosenbrockIntegrator::initialize(const SimTK::State& s) {
  state_ = s;
  system_.realize(state_, SimTK::Stage::Instance);
  if (state_.getNQErr() > 0 || state_.getNUErr() > 0 || state_.getNUDotErr() > 0)
    throw std::invalid_argument(
        "muscle Rosenbrock integrator: the system has constraints or quaternions; use Runge-Kutta-Merson or CPodes BDF");
  if (multibody_) {
    // Prescribed motion is imposed by Simbody's own time steppers (System::prescribe): steps of
    // this integrator would leave the prescribed q and u where they were.
    const SimTK::SimbodyMatterSubsystem& matter = multibody_->getMatterSubsystem();
    for (SimTK::MobilizedBodyIndex b(1); b < matter.getNumBodies(); ++b)
      if (matter.getMobilizedBody(b).getUDotMotionMethod(state_) != SimTK::Motion::Free)
        throw std::invalid_argument("muscle Rosenbrock integrator: mobilized body " + std::to_string(int(b)) +
                                    " has prescribed motion; use Runge-Kutta-Merson or CPodes BDF");
  }
  y_ = s.getY();
  if (!finite(y_)) throw std::invalid_argument("muscle Rosenbrock integrator: the initial state is not finite");
  const int ny = y_.size();
  for (SimTK::Vector* v : {&f0_, &y_stage_, &sum_gamma_, &jv_, &y_new_, &err_}) v->resize(ny);
  for (auto& k : k_) k.resize(ny);
  for (auto& slot : slots_) {
    slot.tendon_index = slot.muscle.getTendonLengthYIndex(state_);
    if (slot.tendon_index < 0 || slot.tendon_index + 1 >= ny)
      throw std::invalid_argument("muscle Rosenbrock integrator: a muscle is not part of this system");
    slot.path.clear();
    const auto& arguments = slot.muscle.getPath().arguments;
    for (std::size_t k = 0; k < arguments.size(); ++k) {
      const SimTK::MobilizedBody& mobilizer = arguments[k].mobilizer;
      if (mobilizer.isEmptyHandle()) continue;  // a held coordinate
      const SimTK::SubsystemIndex matter = mobilizer.getMatterSubsystem().getMySubsystemIndex();
      PathCoupling c;
      c.argument = static_cast<int>(k);
      c.q_index = static_cast<int>(state_.getQStart()) + static_cast<int>(state_.getQStart(matter)) +
                  static_cast<int>(mobilizer.getFirstQIndex(state_));
      c.u_index = static_cast<int>(state_.getUStart()) + static_cast<int>(state_.getUStart(matter)) +
                  static_cast<int>(mobilizer.getFirstUIndex(state_));
      slot.path.push_back(c);
    }
  }
  // Error scales: tendon length by its stretch at Fmax, activation absolutely; 0 for the
  // multibody states (rad, rad/s: relative above 1, computed per step).
  error_scale_.assign(static_cast<std::size_t>(ny), 0.0);
  for (const auto& slot : slots_) {
    error_scale_[static_cast<std::size_t>(slot.tendon_index)] = slot.stretch_scale_m;
    error_scale_[static_cast<std::size_t>(slot.tendon_index) + 1] = 1.0;
  }
  for (std::size_t a = 0; a < slots_.size(); ++a)
    for (std::size_t b = a + 1; b < slots_.size(); ++b)
      if (slots_[a].tendon_index == slots_[b].tendon_index)
        throw std::invalid_argument("muscle Rosenbrock integrator: muscle '" + slots_[a].muscle.getParameters().name +
                                    "' is listed twice");
  direct_derivatives_ = dynamicsStageGivesTheDerivatives();
  // The step size of the previous interval is kept: inputs changing at a control period do not
  // force the cold start an implicit multistep method needs (unless the last run collapsed it).
  if (!(h_ >= kMinStep)) h_ = kFirstStep;
  initialized_ = true;
  f0_valid_ = false;
}

void MuscleRosenbrockIntegrator::derivativesFromDynamicsStage(SimTK::State& s, SimTK::Vector& ydot) {
  system_.realize(s, SimTK::Stage::Dynamics);
  multibody_->getMatterSubsystem().calcAccelerationIgnoringConstraints(
      s, multibody_->getMobilityForces(s, SimTK::Stage::Dynamics), multibody_->getRigidBodyForces(s, SimTK::Stage::Dynamics),
      udot_, body_accelerations_);
  const SimTK::Vector& qdot = s.getQDot();
  const int nq = s.getNQ(), nu = s.getNU();
  for (int i = 0; i < nq; ++i) ydot[i] = qdot[i];
  for (int i = 0; i < nu; ++i) ydot[nq + i] = udot_[i];
  for (const auto& slot : slots_) {
    ydot[slot.tendon_index] = slot.muscle.getTendonLengthDerivative(s);
    ydot[slot.tendon_index + 1] = slot.muscle.getActivationDerivative(s);
  }
}

bool MuscleRosenbrockIntegrator::dynamicsStageGivesTheDerivatives() {
  if (!multibody_ || state_.getNZ() != 2 * static_cast<int>(slots_.size())) return false;
  const auto lock = detail::lock_system_dynamics(system_);  // realizes to Dynamics and beyond
  SimTK::State probe = state_;
  SimTK::Vector direct(y_.size()), staged(y_.size());
  probe.updY() = y_;
  derivativesFromDynamicsStage(probe, direct);
  probe.updY() = y_;
  system_.realize(probe, SimTK::Stage::Acceleration);
  staged = probe.getYDot();
  for (int i = 0; i < staged.size(); ++i)
    if (!(std::abs(direct[i] - staged[i]) <= 1e-10 * (1.0 + std::abs(staged[i])))) return false;
  return true;
}

bool MuscleRosenbrockIntegrator::evaluate(SimTK::State& s, double t, const SimTK::Vector& y, SimTK::Vector& ydot,
                                          bool with_jacobian) {
  s.updTime() = t;
  s.updY() = y;
  if (direct_derivatives_) derivativesFromDynamicsStage(s, ydot);
  else {
    system_.realize(s, SimTK::Stage::Acceleration);
    ydot = s.getYDot();
  }
  if (with_jacobian)
    for (std::size_t j = 0; j < slots_.size(); ++j) {
      const auto d = slots_[j].muscle.getTendonLengthDerivativePartials(s);
      j_ll_[j] = d.d_tendon_length_per_s;
      j_la_[j] = d.d_activation_m_per_s;
      j_lpath_[j] = d.d_musculotendon_length_per_s;
      j_aa_[j] = slots_[j].muscle.getActivationDerivativePartial(s);
      // Moment arms at this posture. Their change with posture (the second derivative of the
      // length) is left out of the matrix: a W-method keeps its order with any matrix, and the
      // stiff part is the tendon's own row.
      for (auto& arm : slots_[j].path) arm.moment_arm_m = slots_[j].muscle.getMomentArm(s, arm.argument);
    }
  return finite(ydot);
}

void MuscleRosenbrockIntegrator::multiplyJacobian(const SimTK::Vector& v, SimTK::Vector& out) const {
  for (int e = 0; e < out.size(); ++e) out[e] = 0.0;
  for (std::size_t j = 0; j < slots_.size(); ++j) {
    const int i = slots_[j].tendon_index;
    double path = 0.0;
    for (const auto& arm : slots_[j].path)  // dL/dq = -r(q); dL_S/dt = u_f + dL/dt
      path -= arm.moment_arm_m * (j_lpath_[j] * v[arm.q_index] + v[arm.u_index]);
    out[i] = j_ll_[j] * v[i] + j_la_[j] * v[i + 1] + path;
    out[i + 1] = j_aa_[j] * v[i + 1];
  }
}

bool MuscleRosenbrockIntegrator::solveInPlace(double c, SimTK::Vector& r) const {
  for (std::size_t j = 0; j < slots_.size(); ++j) {
    const int i = slots_[j].tendon_index;
    const double pivot_a = 1.0 - c * j_aa_[j], pivot_l = 1.0 - c * j_ll_[j];
    if (!(pivot_a >= kMinPivot && pivot_l >= kMinPivot)) return false;
    // Rows of W = I - c J: multibody rows are identity (their entries are already final), the
    // activation row has only its diagonal, the tendon row couples to a and to the path's q, u.
    const double ka = r[i + 1] / pivot_a;
    r[i + 1] = ka;
    double coupled = j_la_[j] * ka;
    for (const auto& arm : slots_[j].path)
      coupled -= arm.moment_arm_m * (j_lpath_[j] * r[arm.q_index] + r[arm.u_index]);
    r[i] = (r[i] + c * coupled) / pivot_l;
  }
  return true;
}

bool MuscleRosenbrockIntegrator::tryStep(double h, double& error_norm) {
  const double t = state_.getTime();
  if (!f0_valid_) {
    if (!evaluate(state_, t, y_, f0_, true)) return false;
    f0_valid_ = true;
  }
  // (I - h gamma J) k_i = h f(t + alpha_i h, y + sum_j alpha_ij k_j) + h J sum_j gamma_ij k_j
  // Element loops throughout: SimTK's vector expressions allocate a temporary per operation.
  const int ny = y_.size();
  for (int i = 0; i < kStages; ++i) {
    double alpha_i = 0.0;
    for (int j = 0; j < i; ++j) alpha_i += kAlpha[i][j];
    for (int e = 0; e < ny; ++e) {
      double stage = y_[e], coupling = 0.0;
      for (int j = 0; j < i; ++j) {
        stage += kAlpha[i][j] * k_[j][e];
        coupling += kGammaOff[i][j] * k_[j][e];
      }
      y_stage_[e] = stage;
      sum_gamma_[e] = coupling;
    }
    if (i == 0) {
      k_[0] = f0_;
    } else if (!evaluate(state_, t + alpha_i * h, y_stage_, k_[i], false)) {
      return false;
    }
    if (i > 0) multiplyJacobian(sum_gamma_, jv_);
    for (int e = 0; e < ny; ++e) k_[i][e] = h * (k_[i][e] + (i > 0 ? jv_[e] : 0.0));
    if (!solveInPlace(kGamma * h, k_[i])) return false;
  }
  for (int e = 0; e < ny; ++e) {
    double next = y_[e], err = 0.0;
    for (int i = 0; i < kStages; ++i) {
      next += kB[i] * k_[i][e];
      err += (kB[i] - kBHat[i]) * k_[i][e];
    }
    y_new_[e] = next;
    err_[e] = err;
  }
  if (!finite(y_new_)) return false;
  // The embedded solution is not L-stable: after an input change it reports the muscle's fast
  // tendon transient, which the main solution damps, as error. Filtering the estimate through
  // W^-1 once more (as RADAU5 does) removes that stiff part and leaves the smooth part as is.
  if (!solveInPlace(kGamma * h, err_)) return false;

  // Per state in its natural scale (error_scale_): muscle states fixed, the others relative above 1.
  error_norm = 0.0;
  for (int i = 0; i < y_.size(); ++i) {
    const double scale = error_scale_[static_cast<std::size_t>(i)] > 0.0 ? error_scale_[static_cast<std::size_t>(i)]
                                                                          : std::max(1.0, std::abs(y_[i]));
    error_norm = std::max(error_norm, std::abs(err_[i]) / (accuracy_ * scale));
  }
  return std::isfinite(error_norm);
}

void MuscleRosenbrockIntegrator::setFixedStepSize(double h) {
  if (!(h >= 0.0) || !std::isfinite(h)) throw std::invalid_argument("fixed step size must be >= 0 s (0: adaptive)");
  fixed_step_ = h;
  if (h > 0.0) h_ = h;
}

bool MuscleRosenbrockIntegrator::advanceUnchecked(double t_end) { return advanceUnchecked(t_end, {}, Report()); }

void MuscleRosenbrockIntegrator::inputsChanged() {
  f0_valid_ = false;  // the excitations (discrete variables) changed: f and J must be re-evaluated
  // Continuous states edited through updState() are taken over, as Simbody's restart does.
  if (!finite(state_.getY())) throw std::invalid_argument("muscle Rosenbrock integrator: the changed state is not finite");
  y_ = state_.getY();
}

void MuscleRosenbrockIntegrator::reportDense(double t0, double h, const std::vector<double>& times,
                                             std::size_t& next, double t_reached, const Report& report) {
  // Uses state_ as workspace: the caller puts the step's end state back afterwards.
  while (next < times.size() && times[next] <= t_reached) {
    const double theta = std::clamp((times[next] - t0) / h, 0.0, 1.0);
    double weight[kStages];
    for (int i = 0; i < kStages; ++i) {
      weight[i] = 0.0;
      double power = theta;
      for (int j = 0; j < 3; ++j, power *= theta) weight[i] += kDense[i][j] * power;
    }
    for (int e = 0; e < y_.size(); ++e) {
      double v = y_[e];
      for (int i = 0; i < kStages; ++i) v += weight[i] * k_[i][e];
      y_stage_[e] = v;
    }
    state_.updTime() = times[next];
    state_.updY() = y_stage_;
    if (report) report(state_);
    ++next;
  }
}

bool MuscleRosenbrockIntegrator::advanceUnchecked(double t_end, const std::vector<double>& report_times,
                                                  const Report& report) {
  const auto lock = detail::lock_system_dynamics(system_);
  if (!initialized_) throw std::logic_error("muscle Rosenbrock integrator: advanceTo before initialize");
  std::size_t next_report = 0;  // the times are in (now, t_end], ascending (checked by Stepper::advanceTo)
  while (state_.getTime() < t_end) {
    if (stepLimitReached()) return false;
    const double t = state_.getTime(), remaining = t_end - t;
    if (!f0_valid_) {
      // Not finite at the start of the step: no step size helps.
      if (!evaluate(state_, t, y_, f0_, true)) return false;
      f0_valid_ = true;
    }
    // Land exactly on t_end; rather two equal steps than a full one and a costly sliver.
    const bool last = h_ >= remaining * (1.0 - 1e-10) || remaining - h_ < 1e-3 * h_;
    const double h = last ? remaining : (remaining < 2.0 * h_ ? 0.5 * remaining : h_);
    double err = 0.0;
    const bool ok = tryStep(h, err);
    const double factor =
        ok ? std::clamp(kSafety * std::pow(std::max(err, 1e-16), -1.0 / (kOrderEmbedded + 1)), kMaxShrink, kMaxGrowth)
           : kMaxShrink;
    if (!(ok && (err <= 1.0 || fixed_step_ > 0.0))) {
      // The stages were evaluated on state_: put the step's start back.
      state_.updTime() = t;
      state_.updY() = y_;
    }
    if (fixed_step_ > 0.0) {
      if (!ok) return false;
      err = 0.0;  // no error control: every finite step is accepted
    }
    if (ok && err <= 1.0) {
      ++accepted_;
      const double t_new = last ? t_end : t + h;
      reportDense(t, h, report_times, next_report, t_new, report);  // y_ and k_ still hold this step
      y_ = y_new_;
      state_.updTime() = t_new;
      state_.updY() = y_;
      f0_valid_ = false;
      if (fixed_step_ > 0.0) continue;
      const double growth = std::min(factor, previous_rejected_ ? 1.0 : kMaxGrowth);
      // A step shortened to land on t_end says nothing against the longer step size.
      h_ = last ? std::max(h_, h * growth) : h * growth;
      previous_rejected_ = false;
    } else {
      ++rejected_;
      h_ = h * std::min(factor, kSafety);
      previous_rejected_ = true;
      // Relative to t as well: t + h must still differ from t.
      if (h_ < std::max(kMinStep, 1e-14 * std::abs(t))) return false;
    }
  }
  return true;
}

}  // namespace flatsos::plugin
