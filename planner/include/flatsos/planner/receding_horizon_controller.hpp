#pragma once
// The receding-horizon (RH) controller of the paper (docs/method/receding_horizon.md), a
// plugin::Controller that drives Simbody muscles through their excitation inputs. Every control
// period delta: take the measured q, qd (and qdd, for the observer; the closed loop's sensors
// give them, late and noisy if asked; a non-finite one is replaced by the last valid one and
// counted), update the disturbance observer, plan one RH step (cubic to the target over the horizon, torque box, SLP),
// evaluate the plan's excitations on the first period by the exact inverse map, and give each
// muscle a polynomial signal over [t, t + delta]. The step keeps the excitations of those
// samples in [0, 1] (and activations in [floor, 1]) by construction unless the options turn its
// bounds off (plan.excitation_bounds.enforce); any sample outside [0, 1] (such a step, or a
// previous plan's tail after a failed step) is clamped by the muscle and counted here. A failed
// step never stops the loop: the previous plan's tail, with the torque offset it was planned
// for, is used and the failure recorded. So is a plan that missed its compute deadline
// (DeadlineOptions): it came too late for its period. Faults are counted by kind (faults()).
//
// Prepared once in the constructor (validated options, the planner's workspace, the excitation
// fit's solution operator); per period only the feedback work remains, in storage the controller
// owns: with the exact SLP solver (SlpSolver::VertexEnumeration) a control period allocates no
// heap memory after the first one, unless keep_history records it (tested by counting
// allocations, tests/realtime). That holds for a set point; a tracking step allocates (its rows
// are too many for the vertex enumeration, and Clp's dual simplex builds its program each time).

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there

#include <functional>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <Simbody.h>

#include "flatsos/planner/disturbance_observer.hpp"
#include "flatsos/planner/excitation_fitter.hpp"
#include "flatsos/planner/muscle_state_estimator.hpp"
#include "flatsos/planner/plan_excitations.hpp"
#include "flatsos/planner/receding_horizon_step.hpp"
#include "flatsos/planner/step_time_histogram.hpp"
#include "flatsos/plugin/integration/closed_loop.hpp"
#include "flatsos/plugin/io/state_table.hpp"

namespace flatsos::planner {

/// The planning step a controller calls, writing into the step it is given (the controller's
/// own, reused every period); replaceable (another planner, or fault injection in tests).
/// Default: the in-place plan_receding_horizon_step. A planner that changes the step it got from
/// there clears its first_period_sampled (the controller applies those samples when set).
using RecedingHorizonPlanner =
    std::function<void(const FlatOutputMap&, plugin::ModelWorkspace&, const Eigen::VectorXd& q_rad,
                       const Eigen::VectorXd& qd_rad_per_s, const RecedingHorizonOptions&, RecedingHorizonStep& out)>;

/// A set point from a time on: the target of every step planned at or after time_s.
struct Setpoint {
  double time_s = 0.0;
  Eigen::VectorXd target_q_rad;
};

/// The compute deadline of a control step: a plan that takes longer arrives too late for its
/// period and is not used; the previous plan's tail runs instead (counted as a deadline miss).
struct DeadlineOptions {
  double deadline_s = 0.0;              ///< the planning step's wall-time budget; 0: none
  /// For tests of the fallback: this fraction of the steps, drawn at random, miss their
  /// deadline whatever their time (their plan is made and discarded).
  double injected_miss_fraction = 0.0;
  unsigned seed = 1;                    ///< of the injected misses
};

/// What went wrong in a run's control steps, by kind. A step may count under several kinds.
struct ControllerFaults {
  int solver_failures = 0;            ///< the planner found no plan (SolveStatus other than Solved)
  int non_finite_plans = 0;           ///< a plan's excitations were not finite on its first period
  int non_finite_measurements = 0;    ///< a measurement was NaN or infinite: the last valid one was held
  int deadline_misses = 0;            ///< the plan came later than DeadlineOptions::deadline_s (or was made to)
  int longest_miss_run = 0;           ///< the most deadline misses in a row
  int fallbacks = 0;                  ///< steps that ran the previous plan's tail instead of a new plan
  int steps_without_plan = 0;         ///< steps with no plan at all to run: the muscles kept their inputs
};

/// The faults of a closed-loop run by the names its summaries give them (the programs' JSON and
/// Python), the integrator's failure (`integration_finite` false) among them.
std::vector<std::pair<std::string, int>> named_fault_counts(const ControllerFaults& faults,
                                                            bool integration_finite);

/// The observer's offset, as a fraction of a joint's muscle capacity (every muscle's maximum
/// isometric force times its moment arm's size, at the set point), below which the model is
/// taken to explain the motion and quick arrivals are made. A plant 30 % weaker than the paper's
/// arm shows 1.8 % at rest; a push's estimate decays below it within a period after the push.
inline constexpr double kTrustedOffsetOfCapacity = 0.005;

struct RecedingHorizonControllerOptions {
  /// Horizon, grid, target, reserves, SLP solver, excitation bounds (their period and samples
  /// are the controller's own: control_period_s, excitation_samples_per_period).
  RecedingHorizonOptions plan;
  RecedingHorizonPlanner planner = [](const FlatOutputMap& f, plugin::ModelWorkspace& w, const Eigen::VectorXd& q,
                                      const Eigen::VectorXd& qd, const RecedingHorizonOptions& o,
                                      RecedingHorizonStep& out) { plan_receding_horizon_step(f, w, q, qd, o, out); };
  double control_period_s = 0.05;          ///< delta
  int excitation_samples_per_period = 11;  ///< inverse-map samples per period (fitted by a polynomial)
  /// Disturbance observer gain, 1/s (see disturbance_observer.hpp); 0: the paper's controller.
  /// The default ends within 0.1 deg of the target on the paper's arm with a plant of 0.7-1.3
  /// times the model's strength (docs/method/receding_horizon.md), and leaves a plant equal to
  /// the model as the paper's controller runs it.
  double disturbance_observer_gain_per_s = 40.0;
  /// Below 1: a set point's step first plans to come to rest at the target in this fraction of
  /// the horizon, and over the whole horizon only when that plan is not solved (too fast a
  /// transfer for the muscles). The rest cubic over a time T acts on an error like a PD law of
  /// stiffness 6/T^2 and damping 4/T, so a quick arrival corrects errors and pushes near the
  /// target faster, and would amplify model mismatch as much: quick plans are made only while
  /// the disturbance observer (which must be on) finds the model explaining the motion, its
  /// offset within kTrustedOffsetOfCapacity of each joint's muscle capacity (see
  /// docs/reliability.md). They are tried once the error is half of what it was when the set
  /// point changed, and after a failed one once it has halved again. In (0, 1]; never shorter
  /// than the control period. 1: the paper's cubic over the whole horizon.
  double quick_arrival_fraction = 0.5;
  /// Keep every period's record in history() (for analysis and prediction_table). Each record
  /// copies its plan: a few heap allocations per period; off, only last() is kept and the loop
  /// allocates nothing.
  bool keep_history = true;
  /// Set points after the first (plan.target_q_rad until the first of them), ascending times.
  std::vector<Setpoint> setpoints;
  DeadlineOptions deadline;
};

/// A plan the controller runs on: constant flat outputs, the predicted joint motion, when it
/// started, and the torque offset it was planned for (its excitations must use that one).
struct PlanInUse {
  Eigen::VectorXd alpha;             ///< constant Y, N
  JointPath path;                    ///< predicted joint motion (the cubic)
  double start_time_s = 0.0;         ///< simulation time of the plan's t = 0
  Eigen::VectorXd torque_offset_N_m; ///< what the muscles were relieved of when it was planned
  FlatOutputStart flat_start;        ///< where its flat outputs started (empty: constant alpha)
  bool empty() const { return alpha.size() == 0; }
};

struct RecedingHorizonRecord {
  double time_s = 0.0;
  SolveStatus status = SolveStatus::Failed;
  std::string message;
  bool used_previous_plan = false;   ///< this step failed and ran on the previous plan's tail
  bool deadline_missed = false;      ///< its plan came too late (or was made to): not used
  bool measurement_held = false;     ///< its measurement was not finite: the last valid one was used
  bool bounds_imposed = false;       ///< the step's SLP optimum left the excitation bounds: alpha was moved
  /// Tracking: why no plan could start from the muscles' states this period (it started free);
  /// empty when one did.
  std::string free_start_message;
  PlanInUse plan;                    ///< the plan in use for this period (empty: none yet)
  Eigen::VectorXd observer_offset_N_m;  ///< the observer's estimate at this step (what a new plan was asked for)
  int clamped_samples = 0;           ///< excitation samples outside [0, 1] this period
  double plan_seconds = 0.0;         ///< the planning step
  /// Its parts (the last step planned this period): the horizon's grid and rows, the SLP, the
  /// first period's excitation bounds (RecedingHorizonStep's timings).
  double grid_seconds = 0.0, slp_seconds = 0.0, bounds_seconds = 0.0, effort_seconds = 0.0;
  double wall_seconds = 0.0;         ///< the whole control step (observer, plan, excitations)
};

class RecedingHorizonController final : public plugin::Controller {
 public:
  /// `plant`: the model whose States step() reads and drives (same joints and muscles in the same
  /// order as the planner's, other parameters allowed: model mismatch); null: the planner's own.
  /// Throws std::invalid_argument for bad options (naming the field) or a plant of other size.
  RecedingHorizonController(FlatOutputMap planner_map, RecedingHorizonControllerOptions options,
                            std::shared_ptr<const plugin::MusculoskeletalModel> plant = nullptr);

  /// Plans from `measured` and installs the excitation signals of the next period in `state`
  /// (at its time).
  const RecedingHorizonRecord& step(SimTK::State& state, const plugin::JointMeasurement& measured);
  /// The same with the joints measured exactly from `state`.
  const RecedingHorizonRecord& step(SimTK::State& state);
  void control(SimTK::State& state, const plugin::JointMeasurement& measured) override { step(state, measured); }

  /// Every period's record (empty unless options.keep_history).
  const std::vector<RecedingHorizonRecord>& history() const { return history_; }
  /// The latest period's record (kept with or without history); before the first step, empty.
  const RecedingHorizonRecord& last() const { return record_; }
  int steps() const { return steps_; }
  int planFailures() const { return plan_failures_; }
  /// The first failed plan's time and message (kept without the history too; time -1: none).
  double firstFailureTime() const { return first_failure_time_s_; }
  const std::string& firstFailureMessage() const { return first_failure_message_; }
  const ControllerFaults& faults() const { return faults_; }
  /// The longest control step so far (observer, plan, excitations), s.
  double worstStepSeconds() const { return worst_step_s_; }
  /// Every step's wall time (kept without the history, in constant memory).
  const StepTimeHistogram& stepTimes() const { return step_times_; }
  /// The set point in force at time t.
  const Eigen::VectorXd& targetAt(double t) const;
  int clampedSamples() const { return clamped_samples_; }
  /// Steps whose SLP optimum left the excitation bounds on the first period (alpha moved inside).
  int boundedSteps() const { return bounded_steps_; }
  /// The integral of sum_j u_j^2 dt over every period applied so far (the excitations as the
  /// muscles take them, clamped to [0, 1]; Simpson on the period's samples).
  double excitationSquaredIntegral() const { return excitation_squared_integral_; }
  const RecedingHorizonControllerOptions& options() const { return options_; }
  /// Implausible options that were accepted (a target beyond one turn: degrees as radians?).
  std::vector<std::string> warnings() const;
  const FlatOutputMap& flat() const { return flat_; }
  const plugin::MusculoskeletalModel& plant() const { return *plant_; }
  const DisturbanceObserver& observer() const { return observer_; }
  /// The planner's model's muscles under the applied excitations (the observer's prediction).
  const MuscleStateEstimator& muscleEstimator() const { return estimator_; }

 private:
  // A tracking step starts where the plan in use is at t (the first one: where the plant's
  // muscles start): its joint acceleration and jerk and its flat outputs' value and rate, so
  // that the muscles' forces and their rates carry on (a plan that starts from its own muscle
  // states makes the muscles jump to them every period; the errors it leaves are what tracking
  // cannot afford).
  void startFromPlanInUse(const SimTK::State& state, double t);
  // Plans this period's step into step_: a tracking step from the muscles' state, and when that
  // start is refused or its plan fails, again with a free start (said in rec).
  void planStep(const SimTK::State& state, double t, RecedingHorizonRecord& rec);
  // A set point's step: over the quick arrival first where allowed (quick_arrival_fraction),
  // else, or when that plan fails, over the whole horizon.
  void planSetpointStep();
  // Whether the observer is on and its offset is within kTrustedOffsetOfCapacity of each
  // joint's muscle capacity at the set point.
  bool modelExplainsTheMotion() const;
  // Takes the measurement into q_, qd_, qdd_ (holding the last valid one when it is not finite).
  void takeMeasurement(const plugin::JointMeasurement& measured, RecedingHorizonRecord& rec);
  // Updates the observer from the measured motion (q_, qd_, qdd_) at time t.
  void observe(double t);
  // Whether this step's plan is too late to be used (measured or injected).
  bool missedDeadline(double plan_seconds);
  // Gives the muscles (and the observer's estimate of them) the excitations of this period.
  /// The step's counts: failures (and the first one's time and message), faults, clamps.
  void countStep(const RecedingHorizonRecord& rec, bool have_excitations, bool plan_not_finite);
  void applyExcitations(SimTK::State& state, double t);
  // Inverse-map excitations of `plan` over the period from t into excitations_ (samples x
  // muscles); false when they are not finite (the plan left the valid domain).
  bool sampleExcitations(const PlanInUse& plan, double t);

  FlatOutputMap flat_;
  std::shared_ptr<const plugin::MusculoskeletalModel> plant_;
  RecedingHorizonControllerOptions options_;
  plugin::ModelWorkspace workspace_;  ///< the planner model's inverse dynamics
  DisturbanceObserver observer_;
  MuscleStateEstimator estimator_;
  ExcitationFitter fitter_;
  PlanInUse in_use_, candidate_;
  RecedingHorizonRecord record_;
  std::vector<RecedingHorizonRecord> history_;
  int steps_ = 0, plan_failures_ = 0, clamped_samples_ = 0, bounded_steps_ = 0;
  double first_failure_time_s_ = -1.0;
  std::string first_failure_message_;
  ControllerFaults faults_;
  int miss_run_ = 0;
  double worst_step_s_ = 0.0;
  StepTimeHistogram step_times_;
  std::mt19937 miss_random_;
  plugin::JointMeasurement exact_;  ///< step(state)'s measurement
  double excitation_squared_integral_ = 0.0;

  // Storage reused every period (sized in the constructor or on the first period).
  RecedingHorizonOptions plan_options_;  ///< options_.plan with this controller's bounds and the observer's current offset
  RecedingHorizonStep step_;
  Eigen::VectorXd q_, qd_, qdd_, measured_torque_, muscle_torque_;
  Eigen::VectorXd previous_q_, previous_qd_, previous_qdd_;  ///< measured at the previous step
  Eigen::VectorXd quick_target_;  ///< the set point the quick arrival's state below refers to
  double quick_retry_below_rad_ = 0.0;  ///< a quick plan is tried while the largest joint error is below this
  Eigen::VectorXd joint_capacity_N_m_;  ///< muscle_capacity at quick_target_
  PlanExcitationScratch excitation_scratch_;
  Eigen::MatrixXd excitations_;  ///< samples x muscles of the period being planned
  Jet start_joint_jet_, start_flat_jet_;  ///< the plan in use at the step's time: N x 4, p x 3
};

/// A closed-loop run of the controller on its plant (plugin::simulate_closed_loop, control
/// period from the controller), with the settling time and the predicted joint paths.
struct RecedingHorizonRun {
  plugin::ClosedLoopResult loop;
  /// One table per step that ran a plan: 11 points along it, at strictly increasing times
  /// (the step's time + tau), each joint's coordinate value and speed (state-table columns).
  std::vector<plugin::StoTable> predictions;
  double settling_time_s = -1.0;  ///< every joint within the tolerance of the (last) target from then on; -1: never
  /// With set points: per set point (the first: plan.target_q_rad from the start), how long after
  /// it took effect the joints came within the tolerance and stayed there until the next; -1: never.
  std::vector<double> setpoint_settling_s;
  /// Why the task failed, one sentence each: the run became non-finite, never settled, or some
  /// plans failed (the first one's time and message).
  /// Empty: the task (reach the target, stay within the tolerance, every plan solved) succeeded.
  std::vector<std::string> failures;
  bool success() const { return failures.empty(); }
};
/// Settled: every pin within settle_tolerance_rad of the target, every slider within 1 mm.
RecedingHorizonRun run_receding_horizon(RecedingHorizonController& controller, const SimTK::State& initial,
                                        const plugin::ClosedLoopOptions& options,
                                        double settle_tolerance_rad = 3.14159265358979323846 / 180.0);

/// "N of M plans failed ...", with the first failure's time and message: a run's failure
/// sentence (run_receding_horizon, run_tracking).
std::string plan_failures_sentence(const RecedingHorizonController& controller);

/// The predicted joint paths of the controller's history (see RecedingHorizonRun::predictions).
std::vector<plugin::StoTable> prediction_tables(const RecedingHorizonController& controller);

}  // namespace flatsos::planner
