#include "flatsos/plugin/integration/stepper.hpp"

#include <algorithm>

#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>
#include <stdexcept>

#include "flatsos/plugin/integration/forward_simulation.hpp"
#include "flatsos/plugin/integration/muscle_rosenbrock_integrator.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"
#include "system_dynamics_lock.hpp"

namespace flatsos::plugin {

namespace {
// Simbody's own integrators behind the Stepper interface.
class SimbodyStepper final : public Stepper {
 public:
  SimbodyStepper(std::unique_ptr<SimTK::Integrator> integrator, const SimTK::System& system)
      : integ_(std::move(integrator)), system_(system) {}

  void initialize(const SimTK::State& s) override {
    const auto lock = detail::lock_system_dynamics(system_);
    pending_ = false;
    integ_->initialize(s);
    counted_ = integ_->getNumStepsTaken();
    counted_attempts_ = integ_->getNumStepsAttempted();
  }
  bool advanceUnchecked(double t) override {
    const auto lock = detail::lock_system_dynamics(system_);
    if (pending_) inputsChanged();
    bool failed = false;
    try {
      // The first stepTo after initialize() only reports the start of the interval without
      // advancing: step until t is really reached.
      // stepTo returns after every internal step, so that a step limit is kept exactly (CPodes
      // reads a limit on internal steps only when it starts). Always, not only with a limit: the
      // same run with and without one is the same to the bit (measured: no slower).
      integ_->setReturnEveryInternalStep(true);
      while (integ_->getTime() < t && all_states_finite(integ_->getState()) && !stepLimitReached()) {
        const auto status = integ_->stepTo(t);
        count();
        if (status == SimTK::Integrator::EndOfSimulation) break;
      }
    } catch (const std::exception&) {
      failed = true;  // StepFailed (step size collapsed) or the model threw: the contract is false
    }
    count();
    return !failed && all_states_finite(integ_->getState()) && integ_->getTime() >= t;
  }
  const SimTK::State& state() const override { return pending_ ? changed_ : integ_->getState(); }
  // getState() may be interpolated (the advanced state lies beyond it): a controller changes
  // a copy, and the integrator restarts from it (CPodes cold: order 1, small steps).
  SimTK::State& updState() override {
    if (!pending_) changed_ = integ_->getState();
    pending_ = true;
    return changed_;
  }
  void inputsChanged() override {
    if (pending_) initialize(changed_);
  }
  long stepsTaken() const override { return steps_; }
  long stepsAttempted() const override { return attempts_; }

 private:
  std::unique_ptr<SimTK::Integrator> integ_;
  const SimTK::System& system_;
  SimTK::State changed_;
  bool pending_ = false;  // changed_ holds edits not yet handed to the integrator
  long steps_ = 0, counted_ = 0, attempts_ = 0, counted_attempts_ = 0;

  void count() {
    steps_ += integ_->getNumStepsTaken() - counted_;
    counted_ = integ_->getNumStepsTaken();
    attempts_ += integ_->getNumStepsAttempted() - counted_attempts_;
    counted_attempts_ = integ_->getNumStepsAttempted();
  }
};
}  // namespace

void check_times(double now, double t_end, const std::vector<double>& report_times, bool have_report) {
  const auto fail = [](const std::string& why) { throw std::invalid_argument("integrator: " + why); };
  const auto time = [](double t) {
    std::ostringstream s;
    s << std::setprecision(17) << t << " s";
    return s.str();
  };
  if (!std::isfinite(t_end)) fail("the target time is not finite");
  if (t_end < now) fail("the target time " + time(t_end) + " lies before the current time " + time(now));
  if (!report_times.empty() && !have_report) fail("report times given but no report callback");
  double previous = now;
  for (std::size_t i = 0; i < report_times.size(); ++i) {
    const double t = report_times[i];
    const auto which = [&] { return "report time " + std::to_string(i) + " (" + time(t) + ")"; };  // only to fail
    if (!std::isfinite(t)) fail("report time " + std::to_string(i) + " is not finite");
    if (t > t_end) fail(which() + " lies after the target time " + time(t_end));
    if (!(t > previous)) fail(which() + (i == 0 ? " is not after the current time " + time(now) : " is not after the one before it"));
    previous = t;
  }
}

bool Stepper::advanceTo(double t) {
  check_times(state().getTime(), t, {}, false);
  return advanceUnchecked(t);
}

bool Stepper::advanceTo(double t_end, const std::vector<double>& report_times, const Report& report) {
  check_times(state().getTime(), t_end, report_times, static_cast<bool>(report));
  return advanceUnchecked(t_end, report_times, report);
}

bool Stepper::advanceUnchecked(double t_end, const std::vector<double>& report_times, const Report& report) {
  for (double t : report_times) {
    if (!advanceUnchecked(t)) return false;
    report(state());
  }
  return advanceUnchecked(t_end);
}

const char* integrator_name(IntegratorKind kind) {
  switch (kind) {
    case IntegratorKind::RungeKuttaMerson: return "rkm";
    case IntegratorKind::CPodesBdf: return "bdf";
    case IntegratorKind::MuscleRosenbrock: return "rosenbrock";
    case IntegratorKind::Automatic: return "auto";
  }
  return "?";
}

IntegratorKind integrator_from_name(const std::string& name) {
  for (auto kind : {IntegratorKind::RungeKuttaMerson, IntegratorKind::CPodesBdf, IntegratorKind::MuscleRosenbrock,
                    IntegratorKind::Automatic})
    if (name == integrator_name(kind)) return kind;
  throw std::invalid_argument("unknown integrator '" + name + "' (rkm, bdf, rosenbrock or auto)");
}

namespace {
// Runge-Kutta-Merson's stability interval on the negative real axis, about: steps of h |lambda|
// up to it are stable (arm26 with DeGroote-Fregly muscles, lambda = -7.9e5 1/s: 2.6e5 steps
// predicted for 1 s, 2.57e5 taken at accuracy 1e-10).
constexpr double kExplicitStability = 3.0;
}  // namespace

IntegratorKind resolve_integrator(const MusculoskeletalModel& model, const SimTK::State& initial, double duration_s,
                                  IntegratorKind requested) {
  if (requested != IntegratorKind::Automatic) return requested;
  SimTK::State s = initial;
  model.system().realize(s, SimTK::Stage::Velocity);
  double fastest_per_s = 0.0;
  for (int j = 0; j < model.numMuscles(); ++j) {
    const HillMuscle& muscle = model.muscle(j);
    fastest_per_s = std::max({fastest_per_s, std::abs(muscle.getTendonLengthDerivativePartials(s).d_tendon_length_per_s),
                              std::abs(muscle.getActivationDerivativePartial(s))});
  }
  const double explicit_steps = duration_s * fastest_per_s / kExplicitStability;
  return explicit_steps > kStiffExplicitSteps ? IntegratorKind::CPodesBdf : IntegratorKind::RungeKuttaMerson;
}

std::unique_ptr<Stepper> make_stepper(const SimTK::System& system, const std::vector<HillMuscle>& muscles,
                                               IntegratorKind kind, double accuracy) {
  if (!(accuracy > 0.0 && accuracy < 1.0)) throw std::invalid_argument("integrator accuracy must be in (0, 1)");
  std::unique_ptr<SimTK::Integrator> integ;
  switch (kind) {
    case IntegratorKind::MuscleRosenbrock:
      return std::make_unique<MuscleRosenbrockIntegrator>(system, muscles, accuracy);
    case IntegratorKind::CPodesBdf:
      integ = std::make_unique<SimTK::CPodesIntegrator>(system, SimTK::CPodes::BDF, SimTK::CPodes::Newton);
      break;
    case IntegratorKind::RungeKuttaMerson:
      integ = std::make_unique<SimTK::RungeKuttaMersonIntegrator>(system);
      break;
    case IntegratorKind::Automatic:
      throw std::invalid_argument("make_stepper: resolve the automatic integrator first (resolve_integrator)");
  }
  integ->setAccuracy(accuracy);
  return std::make_unique<SimbodyStepper>(std::move(integ), system);
}

std::unique_ptr<Stepper> make_stepper(const MusculoskeletalModel& model, IntegratorKind kind,
                                               double accuracy) {
  // Copies of the model's muscle handles change their shared count, which Simbody does not
  // guard: taken and released under the model's lock (declared first, released last), as threads
  // simulating one model make their steppers at once.
  const auto lock = detail::lock_system_dynamics(model.system());
  std::vector<HillMuscle> muscles;
  for (int j = 0; j < model.numMuscles(); ++j) muscles.push_back(model.muscle(j));
  return make_stepper(model.system(), muscles, kind, accuracy);
}

}  // namespace flatsos::plugin
