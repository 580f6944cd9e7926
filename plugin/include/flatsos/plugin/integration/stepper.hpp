#pragma once
// One interface over the integrators a muscle-driven Simbody system can be advanced with, so
// that forward simulations and closed loops share one stepping loop:
//  - Simbody's Runge-Kutta-Merson (explicit; fine unless a tendon is loaded at tiny activation),
//  - Simbody's CPodes BDF (implicit, numerical Jacobian; restarts whenever inputs change),
//  - MuscleRosenbrockIntegrator (linearly implicit in each muscle's own states, explicit in the
//    multibody; keeps its step size across input changes). See muscle_rosenbrock_integrator.hpp.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Simbody.h>

#include "flatsos/plugin/force/hill_muscle.hpp"

namespace flatsos::plugin {

class MusculoskeletalModel;

/// Explicit Runge-Kutta-Merson, CPodes' implicit BDF, the muscle Rosenbrock-W method, or the
/// first two chosen by the muscles' stiffness at the start (resolve_integrator).
enum class IntegratorKind { RungeKuttaMerson, CPodesBdf, MuscleRosenbrock, Automatic };

/// The contract of Stepper::advanceTo, checked in one place for every stepper: `t_end` finite and
/// not before `now`; report times finite, strictly ascending and each in (now, t_end]; a
/// callback when there are report times. Throws std::invalid_argument naming the time and why.
void check_times(double now, double t_end, const std::vector<double>& report_times, bool have_report);

/// "rkm", "bdf", "rosenbrock", "auto" (the command-line names) and back; the inverse throws
/// std::invalid_argument naming the unknown name.
const char* integrator_name(IntegratorKind kind);
IntegratorKind integrator_from_name(const std::string& name);

/// `requested`, or for Automatic the integrator a run of `duration_s` from `initial` needs: the
/// explicit Runge-Kutta-Merson method unless its stability alone would take more than
/// kStiffExplicitSteps steps, estimated from the muscles' fastest time scale at `initial`
/// (d(dL_S/dt)/dL_S, d(da/dt)/da); then CPodes' BDF. A tendon loaded at tiny activation (Moco's
/// DeGroote-Fregly muscles on arm26 at rest: 7.9e5 1/s) would otherwise take some 250 000 explicit
/// steps per second.
constexpr double kStiffExplicitSteps = 20000;
IntegratorKind resolve_integrator(const MusculoskeletalModel& model, const SimTK::State& initial, double duration_s,
                                  IntegratorKind requested);

class Stepper {
 public:
  /// Receives the state at a report time (valid during the call only).
  using Report = std::function<void(const SimTK::State&)>;

  virtual ~Stepper() = default;
  /// Starts (or restarts) from `s`.
  virtual void initialize(const SimTK::State& s) = 0;
  /// Advances exactly to time t (t == now: nothing to do). Returns false when the state became
  /// non-finite or the integrator could not proceed (the Rosenbrock method then keeps its last
  /// accepted state, Simbody's integrators the state where they stopped). Throws
  /// std::invalid_argument for a t that is not finite or lies before the current time.
  bool advanceTo(double t);
  /// Advances exactly to t_end and calls `report` once at each of `report_times`, in order, with
  /// the state at exactly that time. The times must be strictly ascending and in (now, t_end],
  /// and `report` must be set when there are any (see check_times: std::invalid_argument
  /// otherwise, before anything moves). Steppers with a continuous extension interpolate instead
  /// of cutting their steps at the report times; the others step to each.
  bool advanceTo(double t_end, const std::vector<double>& report_times, const Report& report);
  /// The state at the current time. Not necessarily realized: realize it before reading
  /// accelerations.
  virtual const SimTK::State& state() const = 0;
  /// The state at the current time, for a controller to change its inputs (discrete variables);
  /// call inputsChanged() afterwards; changed continuous states are taken over too. (The Rosenbrock
  /// stepper hands out its own state, no copy; Simbody's integrators a copy they restart from.)
  virtual SimTK::State& updState() = 0;
  virtual void inputsChanged() = 0;
  /// Steps taken since construction.
  virtual long stepsTaken() const = 0;
  /// Steps tried since construction, rejected ones included.
  virtual long stepsAttempted() const = 0;
  /// At most this many steps taken in all (0: no limit): an advance that reaches it stops short
  /// of its target time and returns false, with stepLimitReached() true.
  void setStepLimit(long steps) { step_limit_ = steps; }
  bool stepLimitReached() const { return step_limit_ > 0 && stepsTaken() >= step_limit_; }
  long stepLimit() const { return step_limit_; }

 protected:
  /// advanceTo(t) after the checks.
  virtual bool advanceUnchecked(double t) = 0;
  /// advanceTo(t_end, report_times, report) after the checks; the default steps to each report
  /// time.
  virtual bool advanceUnchecked(double t_end, const std::vector<double>& report_times, const Report& report);

 private:
  long step_limit_ = 0;
};

/// A stepper for `system` whose muscles are `muscles` (used by the Rosenbrock method only).
/// `accuracy` is relative (Simbody's meaning); throws std::invalid_argument outside (0, 1) and
/// for Automatic (resolve_integrator first).
std::unique_ptr<Stepper> make_stepper(const SimTK::System& system, const std::vector<HillMuscle>& muscles,
                                               IntegratorKind kind, double accuracy);
std::unique_ptr<Stepper> make_stepper(const MusculoskeletalModel& model, IntegratorKind kind,
                                               double accuracy);

}  // namespace flatsos::plugin
