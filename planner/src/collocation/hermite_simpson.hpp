#pragma once
// The Hermite-Simpson transcription of the open-loop minimum-effort problem along a prescribed
// joint path (docs/method/collocation.md) as a plain sparse NLP: bounds, objective, constraints,
// Jacobian and Hessian of the Lagrangian in triplet form. No solver types here, so tests can
// check every derivative against finite differences; collocation.cpp hands it to Ipopt.
//
// Variables at each of the P = 2K + 1 points i (mesh points at even i, midpoints at odd i), per
// muscle j, four scaled unknowns (index 4 (i m + j) + k):
//   k = 0: s = (L_S - L_slack) / (eps L_slack), the tendon stretch in units of its stretch at
//          Fmax (s^2 = F / Fmax), so that every state is O(1) whatever the tendon's stiffness;
//   k = 1: a, the activation;   k = 2: n, the excitation;
//   k = 3: v = u / Vmax, the fibre shortening velocity in units of its maximum.
// Constraints, in this order:
//   fibre equilibrium  F(s)/Fmax - a f(L - L_S) g(u) = 0           P m rows
//   joint torques      sum_j A_rj F_j - tau_r = 0 (N m)             (P - 1) N rows (not at
//                      t = 0, where the initial state fixes F: checked when it is built)
//   per interval and muscle: Simpson and interpolation defects of s and a   4 K m rows
//   rest at T          n - a = 0 at the last point                  m rows (free muscle ends:
//                      unbounded)
// (dL_S/dt = 0 at T fixes v there, the initial state fixes s and a at t = 0: bounds.)
// With a free joint path (FreeJoints given), each point also has 3N unknowns q, qd, qdd (index
// 4 m + kind N + r after the muscles), the torque rows hold at t = 0 too (they set qdd(0)), the
// tau are the model's inverse dynamics of the unknowns, the musculotendon lengths and rates
// functions of q and qd, and per interval and joint four more defects (Simpson and interpolation
// of q with rate qd and of qd with rate qdd) come before the rest rows; q and qd are fixed at
// t = 0 and q, qd = 0, qdd = 0 at T.
// Hermite-Simpson represents each state by a C1 piecewise cubic whose slopes at the three
// points of an interval are the dynamics there; the excitation between points is the one those
// cubics imply (the inverse activation dynamics of a and da/dt), not an interpolation of n.
// (Interpolating n instead is not the same trajectory: the optimal n alternates between mesh
// points and midpoints, near 0.4 and 0.05 on the paper's problem.) The midpoint excitations are
// free, not the mean of their interval's ends (OpenSim Moco's interpolate_control_midpoints): the
// reference is the effort's infimum. Where deactivation is slower than activation, an excitation
// switching between 0 and 1 faster than the activation follows costs less than one the activation
// follows (the cost of u against da/dt has a concave kink at u = a), and the free midpoints converge to
// that value as the mesh refines (the arm's free path with squared excitations: 0.09520, 0.09559,
// 0.09562 s on 100, 200, 400 graded intervals); tied, the solves were erratic (0.0971, 0.0964,
// 0.0990 s) and along a prescribed path did not converge in 3000 iterations.
// Time points: mesh points in geometric progression (CollocationOptions::mesh_interval_growth),
// each interval's midpoint halfway.

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "flatsos/muscles/muscle_parameters.hpp"
#include "flatsos/planner/effort.hpp"
#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/joint_paths.hpp"
#include "flatsos/plugin/model/pin_tree_dynamics.hpp"

namespace flatsos::planner::detail {

/// One muscle's data for the transcription.
struct CollocationMuscle {
  muscles::MuscleParameters parameters;
  double reserve_N = 0.0;
  double min_activation = 0.0;
  double initial_stretch = 0.0;     ///< s at t = 0
  double initial_activation = 0.0;  ///< a at t = 0
};

/// The joint path sampled at the collocation points.
struct PathSamples {
  Eigen::VectorXd time_s;                 ///< P = 2K + 1 points on [0, T]: mesh points, each interval's midpoint between
  Eigen::MatrixXd musculotendon_length_m;  ///< m x P
  Eigen::MatrixXd lengthening_rate_m_per_s;  ///< m x P
  Eigen::MatrixXd torque_N_m;             ///< N x P, inverse dynamics along the path
  Eigen::MatrixXd moment_arms_m;          ///< N x m
  /// Posture-dependent arms (N x m at each point) along a prescribed path; empty: moment_arms_m.
  std::vector<Eigen::MatrixXd> moment_arms_at;
  Eigen::MatrixXd q_rad, qd_rad_per_s, qdd_rad_per_s2;  ///< N x P, the joint path itself
};

/// What makes the joint path free: the model's inverse dynamics, the muscles' lengths as
/// functions of q, and the path's ends. (Constant moment arms: L_j(q) = L_j(0) - A_j^T q, so
/// dL_j/dt = -A_j^T qd and neither has curvature; posture-dependent paths add their Hessians.)
struct FreeJoints {
  const plugin::PinTreeDynamics* dynamics = nullptr;  ///< the model's; outlives the problem
  Eigen::VectorXd length_at_zero_angles_m;            ///< L_j(0), m entries
  Eigen::VectorXd start_q_rad, start_qd_rad_per_s;    ///< at t = 0
  Eigen::VectorXd end_q_rad;                          ///< at T, at rest (qd = qdd = 0)
};

/// The path at the 2K + 1 points of K intervals, each `growth` times as long as the one before
/// (1: uniform), inverse dynamics by Simbody.
PathSamples sample_path(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const JointPath& path,
                        int intervals, double growth = 1.0);
/// The free-path data of the model, with the path's ends (it must end at rest; throws
/// std::invalid_argument otherwise).
FreeJoints free_joints(const FlatOutputMap& flat, const JointPath& path);
/// The model's muscles with the problem's reserves, activation floor (0: each muscle's own) and
/// initial state.
std::vector<CollocationMuscle> collocation_muscles(const FlatOutputMap& flat, const MuscleState& initial,
                                                   const Eigen::VectorXd& reserves_N, double min_activation);

class HermiteSimpsonProblem {
 public:
  static constexpr int kPerMuscle = 4;
  enum Unknown { kStretch = 0, kActivation = 1, kExcitation = 2, kVelocity = 3 };
  enum JointUnknown { kAngle = 0, kSpeed = 1, kAcceleration = 2 };

  /// Minimizing `effort` (not null) along the sampled joint path, or (free given) with the path
  /// free between its ends; the samples' path is then only the start. With free_muscle_ends
  /// (along a prescribed path) neither the initial muscle state nor rest at T is imposed.
  HermiteSimpsonProblem(std::vector<CollocationMuscle> muscles, PathSamples samples,
                        std::shared_ptr<const Effort> effort, std::optional<FreeJoints> free = std::nullopt,
                        bool free_muscle_ends = false);

  int points() const { return static_cast<int>(samples_.time_s.size()); }
  int intervals() const { return (points() - 1) / 2; }
  int muscles() const { return static_cast<int>(muscles_.size()); }
  int joints() const { return static_cast<int>(samples_.torque_N_m.rows()); }
  bool freePath() const { return free_.has_value(); }
  int variables() const { return points() * stride(); }
  int constraints() const;
  int jacobianNonzeros() const { return static_cast<int>(jac_rows_.size()); }
  int hessianNonzeros() const { return static_cast<int>(hess_rows_.size()); }
  int index(int point, int muscle, Unknown k) const { return point * stride() + muscle * kPerMuscle + k; }
  /// Free path only.
  int jointIndex(int point, int joint, JointUnknown k) const {
    return point * stride() + muscles() * kPerMuscle + k * joints() + joint;
  }

  const PathSamples& samples() const { return samples_; }
  const CollocationMuscle& muscle(int j) const { return muscles_[j]; }

  void bounds(double* x_lower, double* x_upper, double* g_lower, double* g_upper) const;
  /// A start independent of any planner: at each point the torque split with the least sum of
  /// squared normalized forces, raised to the reserves, the activation holding it isometrically,
  /// n = a; the initial state at t = 0.
  void startingPoint(double* x) const;

  /// The effort's term of muscle j at point i, where its tendon carries tendon_force_N.
  MuscleEffortJet effortTerm(const double* x, int point, int muscle, double tendon_force_N) const;
  double objective(const double* x) const;  ///< the effort's integral (Simpson), in Effort::unit()
  void objectiveGradient(const double* x, double* gradient) const;
  void constraintValues(const double* x, double* g) const;
  /// Triplets in a fixed order (no duplicates); the values are filled in that order.
  const std::vector<int>& jacobianRows() const { return jac_rows_; }
  const std::vector<int>& jacobianColumns() const { return jac_cols_; }
  void jacobianValues(const double* x, double* values) const;
  /// Lower triangle (row >= column) of objective_factor * Hess(objective) + sum_r
  /// multipliers_r Hess(g_r): one 4 x 4 block per point and muscle (free path: and each muscle's
  /// q rows, and the 3N x 3N joint block of each point).
  const std::vector<int>& hessianRows() const { return hess_rows_; }
  const std::vector<int>& hessianColumns() const { return hess_cols_; }
  void hessianValues(const double* x, double objective_factor, const double* multipliers, double* values) const;

  /// Quantities in SI units at a point.
  double tendonForce(const double* x, int point, int muscle) const;
  double tendonLength(const double* x, int point, int muscle) const;
  /// The scaled stretch s at which muscle's tendon carries force_N (0 for force_N <= 0).
  double stretchAtForce(int muscle, double force_N) const;
  double shorteningVelocity(const double* x, int point, int muscle) const;
  double activationRate(const double* x, int point, int muscle) const;  ///< sigma(n) (n - a), 1/s
  /// The joint path at a point (the unknowns, or the samples along a prescribed path).
  double joint(const double* x, int point, int joint, JointUnknown k) const;
  double musculotendonLength(const double* x, int point, int muscle) const;
  double lengtheningRate(const double* x, int point, int muscle) const;  ///< dL/dt, m/s

 private:
  // Every Jacobian (Hessian) entry in its fixed order: sink(row, column, value). One routine for
  // structure and values keeps them in step.
  template <class Sink>
  void visitJacobian(const double* x, Sink&& sink) const;
  template <class Sink>
  void visitHessian(const double* x, double objective_factor, const double* multipliers, Sink&& sink) const;
  // The joint defects are linear: term(column, coefficient) for each unknown of row `which`
  // (0, 1: Simpson, interpolation of q; 2, 3: of qd) of interval k and joint r.
  template <class Term>
  void visitJointDefect(int interval, int joint, int which, Term&& term) const;
  struct MuscleAt;  // the laws and their derivatives with respect to the scaled unknowns
  MuscleAt evaluate(const double* x, int point, int muscle) const;

  int stride() const { return muscles() * kPerMuscle + (freePath() ? 3 * joints() : 0); }
  int firstTorquePoint() const { return freePath() || free_muscle_ends_ ? 0 : 1; }
  const Eigen::MatrixXd& armsAt(int point) const {
    return samples_.moment_arms_at.empty() ? samples_.moment_arms_m : samples_.moment_arms_at[static_cast<std::size_t>(point)];
  }
  int equilibriumRow(int point, int muscle) const { return point * muscles() + muscle; }
  // Along a prescribed path point 0 has no torque rows: the initial state fixes every tendon
  // force there. With a free path they set qdd(0); with free muscle ends they hold as anywhere.
  int torqueRow(int point, int joint) const {
    return points() * muscles() + (point - firstTorquePoint()) * joints() + joint;
  }
  int defectRow(int interval, int muscle, int which) const {
    return torqueRow(points(), 0) + (interval * muscles() + muscle) * 4 + which;
  }
  // Free path: 0, 1 Simpson and interpolation of q (rate qd); 2, 3 of qd (rate qdd).
  int jointDefectRow(int interval, int joint, int which) const {
    return defectRow(intervals(), 0, 0) + (interval * joints() + joint) * 4 + which;
  }
  int restRow(int muscle) const {
    return (freePath() ? jointDefectRow(intervals(), 0, 0) : defectRow(intervals(), 0, 0)) + muscle;
  }
  // tau at a point (free path: inverse dynamics of the unknowns).
  Eigen::VectorXd torque(const double* x, int point) const;
  Eigen::VectorXd jointVector(const double* x, int point, JointUnknown k) const;
  double quadratureWeight(int point) const;  // Simpson's weight of the point, s
  double intervalLength(int interval) const { return samples_.time_s[2 * interval + 2] - samples_.time_s[2 * interval]; }

  std::vector<CollocationMuscle> muscles_;
  PathSamples samples_;
  std::shared_ptr<const Effort> effort_;
  std::optional<FreeJoints> free_;
  bool free_muscle_ends_ = false;
  std::vector<double> stretch_scale_m_;  // eps L_slack
  std::vector<int> jac_rows_, jac_cols_, hess_rows_, hess_cols_;
};

}  // namespace flatsos::planner::detail
