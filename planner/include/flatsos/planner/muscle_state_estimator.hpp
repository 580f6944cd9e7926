#pragma once
// What the planner's model predicts the plant's muscles do: the model's muscle states (tendon
// length, activation per muscle) driven by the excitations the controller applied, along the
// joint motion it measured. The disturbance observer compares the torque the measured motion
// needs with the torque these muscles give (disturbance_observer.hpp), so a plan that starts
// from other muscle states than the plant's (every receding-horizon plan does: its flat outputs
// are free at its start) is not mistaken for a disturbance.
//
// Between two measurements the joints follow the quintic Hermite through both (q, qd, qdd). Each
// muscle's two states then depend on nothing else, so each is advanced on its own, with its own
// step size: Verwer's ROS2 (a two-stage linearly implicit method of order 2, L-stable: Verwer,
// Spee, Blom and Hundsdorfer 1999, SIAM J. Sci. Comput. 20(4)) with the exact partials in the
// muscle's states and in time (the path's motion and the excitation's change drive the stiff
// tendon: without the time column the accuracy collapses), its error against the embedded
// first-order solution kept below `accuracy` in the states' natural scales (the tendon's stretch
// at Fmax, activation itself), as the plant's Rosenbrock integrator keeps it. A tendon that is
// stiff at low activation, or a muscle that activates sharply, takes short steps; the rest take
// one or two per control period. The laws are the model's own (muscles/hill_laws.hpp), as the
// Simbody force's.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "flatsos/plugin/force/excitation_signal.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace flatsos::planner {

class MuscleStateEstimator {
 public:
  /// Throws std::invalid_argument for a null model or an accuracy outside (0, 0.1].
  explicit MuscleStateEstimator(std::shared_ptr<const plugin::MusculoskeletalModel> model, double accuracy = 1e-5);

  bool started() const { return started_; }
  /// Starts (or restarts) from these states at `time_s`; the excitations keep what was set (0
  /// before any).
  /// Throws std::invalid_argument for wrong sizes or values that are not finite.
  void start(const Eigen::VectorXd& tendon_lengths_m, const Eigen::VectorXd& activations, double time_s);
  /// The excitation muscle j receives from now on (clamped to [0, 1] as the Simbody muscle
  /// clamps it). Throws std::invalid_argument for a piece that fails ExcitationPolynomial::validate.
  void setExcitation(int muscle, const plugin::ExcitationPolynomial& piece);
  /// The joints' measured state at one time: angles, speeds, accelerations.
  struct JointMeasurement {
    const Eigen::VectorXd& q_rad;
    const Eigen::VectorXd& qd_rad_per_s;
    const Eigen::VectorXd& qdd_rad_per_s2;
  };
  /// Advances the muscle states from the current time, where the joints were at `from`, to
  /// `time_s`, where they are at `to`. Allocates nothing. Returns false (states unchanged) when
  /// the inputs or the result are not finite; throws std::logic_error before start() and
  /// std::invalid_argument for a time before the current one.
  bool advance(const JointMeasurement& from, const JointMeasurement& to, double time_s);
  /// R(q) F(L_S): the joint torques the estimated muscles give at posture q (N m; N on a
  /// slider), into `out` (resized once).
  void muscleTorques(const Eigen::VectorXd& q_rad, Eigen::VectorXd& out_N_m) const;

  double time_s() const { return time_s_; }
  const Eigen::VectorXd& tendonLengths_m() const { return tendon_length_m_; }
  const Eigen::VectorXd& activations() const { return activation_; }

 private:
  // The joints' (q, qd, qdd) at time t of the advance into jet_, from the quintic.
  void jointJetAt(double t);
  // d/dt of muscle j's (L_S, a) at time t with the joints at jet_.
  void rates(int j, double t, double tendon_length_m, double activation, double& d_tendon, double& d_activation) const;
  // Muscle j from time_s_ to t_end; false when its steps shrink to nothing or leave finite values.
  bool advanceMuscle(int j, double t_end);
  // One ROS2 step of muscle j from (t, ls, a) by h: the new states and the error's norm
  // (<= 1: accepted); false when W is singular or a value not finite (the step is rejected).
  bool tryStep(int j, double t, double h, double& ls, double& a, double& error_norm);

  std::shared_ptr<const plugin::MusculoskeletalModel> model_;
  double accuracy_;
  bool started_ = false;
  double time_s_ = 0.0;
  Eigen::VectorXd tendon_length_m_, activation_;
  std::vector<plugin::ExcitationPolynomial> excitation_;
  std::vector<double> step_s_;  ///< each muscle's next trial step
  // Scratch of one advance: its start time and duration, the quintic's coefficients in
  // s = (t - start) / duration (joints x 6), the joints' jet at a stage (q, qd, qdd).
  double advance_start_s_ = 0.0, advance_duration_s_ = 1.0;
  Eigen::MatrixXd quintic_;
  Eigen::VectorXd jet_, saved_tendon_m_, saved_activation_;
  mutable Eigen::VectorXd arms_m_;  ///< muscleTorques' scratch: one estimator per thread
};

}  // namespace flatsos::planner
