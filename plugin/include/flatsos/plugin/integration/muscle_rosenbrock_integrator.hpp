#pragma once
// A Rosenbrock-W integrator for Simbody systems driven by HillMuscles: ROS34PW2 of Rang &
// Angermann (BIT 45, 2005): 4 stages, order 3 with an embedded order-2 solution, L-stable.
//
// Why: at small activations a loaded tendon makes dL_S/dt stiff (d(dL_S/dt)/dL_S ~ -1e4 1/s at
// a ~ 1e-3), which holds explicit methods to ~1e-4 s steps, while the multibody part is smooth.
// A W-method keeps its order for ANY matrix in place of the Jacobian. We use the exact rows of
// each muscle's states from the muscle laws: dL_S/dt and da/dt with respect to the muscle's own
// (L_S, a) and to the joint coordinates and speeds its path crosses; the rows of the multibody
// states are zero (explicit). The path columns matter: without them the fast tendon mode cannot
// follow the joint motion that drives it and the accuracy collapses in the stiff regime
// (measured with ROS2: 5x the steps per 10x accuracy instead of ~3x). That matrix is block
// triangular, so a step costs four evaluations of the derivatives (each a realize to Dynamics
// and the tree's accelerations) and a substitution per muscle, no factorization.
//
// Step size: the difference to the embedded solution, filtered through (I - gamma h J)^-1 (so
// a fast tendon transient after an input change is not counted as error), per state in its
// natural scale (rad, rad/s, activation, tendon stretch at Fmax), kept <= accuracy (max norm),
// e.g. 1e-5 bounds a tendon's per-step error at ~1e-5 x 0.04 x slack length. The step size
// survives initialize(), so a controller changing the excitations every period does not force
// the cold start an implicit multistep method (CPodes BDF) needs.
//
// Limits: systems without constraints and without quaternions (Pin/slider trees); other
// continuous z states are integrated explicitly. Throws std::invalid_argument otherwise.

#include <vector>

#include "flatsos/plugin/integration/stepper.hpp"

namespace flatsos::plugin {

class MuscleRosenbrockIntegrator final : public Stepper {
 public:
  /// Keeps copies of the muscles' handles, taken and (on destruction) released under the
  /// system's lock: Simbody's handle counts are not atomic, and threads may simulate one model.
  MuscleRosenbrockIntegrator(const SimTK::System& system, const std::vector<HillMuscle>& muscles, double accuracy);
  ~MuscleRosenbrockIntegrator() override;

  void initialize(const SimTK::State& s) override;
  const SimTK::State& state() const override { return state_; }
  SimTK::State& updState() override { return state_; }
  void inputsChanged() override;
  long stepsTaken() const override { return accepted_; }
  long stepsAttempted() const override { return accepted_ + rejected_; }
  /// Whether the derivatives come from the Dynamics stage (see derivativesFromDynamicsStage);
  /// false: from realize(Acceleration).
  bool usesDynamicsStageDerivatives() const { return direct_derivatives_; }
  /// The step size the next step will try, s.
  double nextStepSize() const { return h_; }
  /// Fixed steps of h seconds without error control (0, the default: adaptive). For
  /// convergence studies and hard real-time use; the last step before a target time is shortened.
  /// A step too long for a muscle's own time scale (see kMinPivot) stops advanceTo (false).
  void setFixedStepSize(double h_s);

 protected:
  /// Reports come from the method's continuous extension (second order with the approximate
  /// Jacobian, within the controlled error): steps are not cut.
  bool advanceUnchecked(double t_end, const std::vector<double>& report_times, const Report& report) override;
  bool advanceUnchecked(double t) override;

 private:
  static constexpr int kStages = 4;
  struct PathCoupling {
    int argument = -1;               // of the muscle's path
    int q_index = -1, u_index = -1;  // in Y
    double moment_arm_m = 0.0;       // dL/dq = -moment_arm, at the last Jacobian's posture
  };
  struct MuscleSlot {
    HillMuscle muscle;
    int tendon_index = -1;  // in Y; activation at +1
    double stretch_scale_m = 0.0;
    std::vector<PathCoupling> path;
  };
  // f(t, y) into ydot (and the muscles' Jacobian rows when `with_jacobian`); false if not finite.
  bool evaluate(SimTK::State& s, double t, const SimTK::Vector& y, SimTK::Vector& ydot, bool with_jacobian);
  // out = J v for the approximate Jacobian J (muscle rows only).
  void multiplyJacobian(const SimTK::Vector& v, SimTK::Vector& out) const;
  // r = (I - c J)^-1 r; false if a pivot is too small (the step is too long for the muscle).
  bool solveInPlace(double c, SimTK::Vector& r) const;
  bool tryStep(double h, double& error_norm);
  // Calls `report` for times[next..] <= t_reached by the continuous extension of the step
  // [t0, t0 + h] just accepted (y_ and k_ still hold it).
  void reportDense(double t0, double h, const std::vector<double>& times, std::size_t& next, double t_reached,
                   const Report& report);

  // ydot from realize(Dynamics): the tree's accelerations under the Dynamics stage's forces
  // (SimbodyMatterSubsystem::calcAccelerationIgnoringConstraints) and the muscles' own state
  // derivatives. realize(Acceleration) adds Simbody's loop forward dynamics and every
  // subsystem's Acceleration stage, the same numbers where there are no constraints, no
  // prescribed motion and no z but the muscles' (checked at initialize against it).
  void derivativesFromDynamicsStage(SimTK::State& s, SimTK::Vector& ydot);
  bool dynamicsStageGivesTheDerivatives();

  const SimTK::System& system_;
  const SimTK::MultibodySystem* multibody_ = nullptr;  // null: not a multibody system
  bool direct_derivatives_ = false;                    // derivativesFromDynamicsStage, else realize(Acceleration)
  SimTK::Vector udot_;
  SimTK::Vector_<SimTK::SpatialVec> body_accelerations_;
  std::vector<MuscleSlot> slots_;
  double accuracy_;
  double fixed_step_ = 0.0;
  SimTK::State state_;  // also the workspace of the stage evaluations
  SimTK::Vector y_, f0_, y_stage_, sum_gamma_, jv_, y_new_, err_;
  SimTK::Vector k_[kStages];
  std::vector<double> error_scale_;  // per Y entry; 0: relative above 1
  std::vector<double> j_ll_, j_la_, j_aa_, j_lpath_;  // per muscle: the Jacobian entries at (t_n, y_n)
  double h_ = 1e-4;  // the next trial step, s
  bool initialized_ = false, f0_valid_ = false, previous_rejected_ = false;
  long accepted_ = 0, rejected_ = 0;
};

}  // namespace flatsos::plugin
