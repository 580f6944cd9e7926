#pragma once
// The joint path as a variable, and the plan's rows over both kinds of coefficient: each joint is
// a clamped B-spline through the open-loop plan's boundary derivatives, q_i = B (particular_i +
// nullspace_i c_i); at each time point and muscle the reserve row F_j >= reserve_j and the four
// bound rows of a and n are functions of z = (theta, c), with their exact Jacobian and the
// Hessian of their multiplier-weighted sum. The path's two optimizers share them
// (docs/method/free_path.md).

#include <array>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "flatsos/planner/joint_paths.hpp"
#include "path/free_path_settings.hpp"
#include "sos/bound_points.hpp"
#include "sos/sos_setup.hpp"

namespace flatsos::planner::detail {

constexpr int kPathOrders = 5;               // q .. q'''' (the excitation needs d2 tau / dt2)
constexpr double kReserveMargin_N = 1e-6;    // reserve rows hold F >= reserve + this

// The joint path's spline: q_i = B (particular_i + nullspace_i c_i), c = [c_0; c_1; ...].
struct PathParameterization {
  explicit PathParameterization(BSplineBasis b) : basis(std::move(b)) {}
  BSplineBasis basis;
  std::vector<OutputParameterization> joints;
  int free = 0;

  Eigen::MatrixXd coefficients(const Eigen::VectorXd& c) const;
  JointPath path(const Eigen::VectorXd& c) const;
};

/// The spline of `o` through q..q''' at 0 (initial: N x 4) and rest at `target` at T.
PathParameterization parameterize(const FreePathSettings& o, double T, const Eigen::MatrixXd& initial,
                                  const Eigen::VectorXd& target);

/// The c whose spline is closest (least squares on a fine grid) to `path`: exact when the
/// spline's space holds it (degree 8: the prescribed path itself).
Eigen::VectorXd fit_to(const PathParameterization& P, const JointPath& path);

/// Everything about one time point that does not depend on the variables.
struct PathPoint {
  BoundPoint flat;                                   // F's flat-output part: base + slope theta
  Eigen::MatrixXd q_base;                            // N x 5: the joint jet at c = 0
  /// The path coefficients the joint jet here depends on (the B-splines' local support: a
  /// handful per joint, whatever the spans), ascending indices into c.
  std::vector<int> path_columns;
  std::array<Eigen::MatrixXd, kPathOrders> q_slope;  // per order: N x path_columns (d q^(l) / d c)

  /// c's entries at path_columns.
  Eigen::VectorXd localPath(const Eigen::VectorXd& c) const;
};

PathPoint make_path_point(const SosSetup& setup, const FlatOutputMap& flat, const PathParameterization& P, double t);

/// The reserve rows' margin at a point: none at t = 0, where the initial state fixes every tendon
/// force and nothing can move it (a minimum-effort rest starts a muscle exactly at its reserve;
/// plan_open_loop checks the reserves at t = 0 itself).
inline double reserve_margin_N(const PathPoint& pt) {
  return pt.flat.t_s > 0.0 ? kReserveMargin_N : 0.0;
}

/// The joint jet (N x 5) of the path of c at a point.
Eigen::MatrixXd joint_jet(const PathPoint& pt, const Eigen::VectorXd& c);
/// Its derivative in the point's path columns: 5N x columns, row 5 r + l for d^l q_r / dt^l.
Eigen::MatrixXd joint_jet_slope(const PathPoint& pt, int joints);
/// The points' tendon-force jets (base plus C_tau tau along the path of c, slope in theta) and
/// path-length jets: BoundPoints over theta for the path c.
std::vector<BoundPoint> bound_points_along_path(const FlatOutputMap& flat, const std::vector<PathPoint>& points,
                                                const Eigen::VectorXd& c);

/// The rows' variables z = (theta, c).
struct PathVariables {
  int thetas = 0, paths = 0;
  int size() const { return thetas + paths; }
  Eigen::VectorXd theta(const Eigen::VectorXd& z) const { return z.head(thetas); }
  Eigen::VectorXd c(const Eigen::VectorXd& z) const { return z.tail(paths); }
};

/// Whether the rows' Hessian holds the torque jet's own curvature in the joint jet.
enum class TorqueCurvature {
  Exact,
  /// Left out: the Hessian of the rows with the torque jet linearized about z (Gauss-Newton in the
  /// torques). The torque jet's exact curvature is 40 fourth-order dual passes per point; on the
  /// arm's free path it cost 5.8 of 14.4 s and saved 12 of 156 Ipopt iterations, to the same
  /// optimum (docs/method/free_path.md, "Speed").
  Linearized,
};

/// Per point and muscle: the reserve row, then the four bound rows, each ">= 0". The Jacobian's
/// pattern does not depend on z: per row, the point's theta columns, then its path columns.
class PathRows {
 public:
  /// Throws std::logic_error for a model whose moment arms vary with the posture: the Hessian
  /// leaves out the path lengths' curvature, which only they have.
  ///
  /// `inverse_curvature_floor`: in lagrangianHessian, a muscle at a point whose four bound rows'
  /// multipliers are all at most this fraction of the largest bound-row multiplier (in
  /// magnitude) adds no curvature of its muscle inverse (the term J_u^T (Hessian of h in u) J_u,
  /// twelve gradients of the inverse). 0: only exactly zero multipliers, the exact Hessian.
  PathRows(const FlatOutputMap& flat, const PathVariables& v, const std::vector<PathPoint>& points,
           const Eigen::VectorXd& reserves, const Eigen::VectorXd& a_min,
           TorqueCurvature curvature = TorqueCurvature::Exact, double inverse_curvature_floor = 0.0);

  static constexpr int kRows = 1 + kRowsPerMuscle;
  int rows() const { return static_cast<int>(points_.size()) * flat_.numMuscles() * kRows; }

  BoundRowsAt operator()(const Eigen::VectorXd& z, bool jacobian) const;
  /// The Jacobian's entries: per row, its point's theta columns, then its path columns.
  std::size_t jacobianEntries() const;
  /// The rows' values (rows() of them) and, unless `jacobian` is null, the Jacobian's values in
  /// the order of operator()'s triplets (jacobianEntries() of them), written in place: what Ipopt
  /// asks for at every iterate, without building the triplets.
  void evaluateInto(const Eigen::VectorXd& z, double* values, double* jacobian) const;

  /// The lower triangle of sum_k lambda_k (Hessian of row k) in z, as triplets in a fixed order
  /// (repeated entries add up): per point, its block over (its theta columns, its path columns).
  ///
  /// Row k is h(u(z)) with u = (F, dF, ddF, L, dL, ddL) of its muscle, so its Hessian is
  /// J_u^T (Hessian of h in u) J_u plus sum_i dh/du_i (Hessian of u_i in z). u is affine in theta,
  /// and in c only through the joint jet (linear in c) and the torque jet and path length of it.
  /// The exact gradient of h in u (muscles::invert_muscle) is differenced centrally in u's 6
  /// entries (second derivatives to about 1e-8 relative without third derivatives of the Hill
  /// laws); the torque jet's Hessian in the joint jet is exact (PinTreeDynamics::torqueJetHessian)
  /// or left out (TorqueCurvature); the path lengths are affine in q (constant moment arms).
  std::vector<Eigen::Triplet<double>> lagrangianHessian(const Eigen::VectorXd& z, const std::vector<double>& lambda) const;
  /// The same values written in place (`lambda`: rows() multipliers): what Ipopt asks for at
  /// every iterate, without building the triplets.
  void lagrangianHessianInto(const Eigen::VectorXd& z, const double* lambda, double* values) const;
  /// The same pattern (values 0).
  std::vector<Eigen::Triplet<double>> hessianPattern() const;

 private:
  template <class Emit>
  void emitRows(const Eigen::VectorXd& z, bool jacobian, double* values, Emit&& emit) const;
  template <class Emit>
  void emitLagrangianHessian(const Eigen::VectorXd& z, const double* lambda, Emit&& emit) const;
  // A point's local variables: its theta columns, then its path columns (indices into z).
  std::vector<int> localVariables(const PathPoint& pt) const;
  // The torque jet at point k along the path of c and its gradient in the joint jet (3N x 5N),
  // computed once per c: Ipopt asks for the Jacobian and the Hessian at the same iterate, and
  // this gradient (dual numbers through the pin tree) was half of either's time.
  struct TorqueJetAt {
    Eigen::MatrixXd tau, gradient;
  };
  const TorqueJetAt& torqueJetAt(std::size_t k, const Eigen::VectorXd& c) const;
  // `skip_below`: a muscle whose bound-row multipliers are all at most this adds no inverse curvature.
  Eigen::MatrixXd pointHessian(std::size_t k, const Eigen::VectorXd& theta, const Eigen::VectorXd& c,
                               const double* lambda, double skip_below) const;

  const FlatOutputMap& flat_;
  const PathVariables& v_;
  const std::vector<PathPoint>& points_;
  const Eigen::VectorXd& reserves_;
  const Eigen::VectorXd& a_min_;
  TorqueCurvature curvature_;
  double inverse_curvature_floor_;
  // torqueJetAt's memory: the c it holds the points' jets for, and which points it has.
  mutable Eigen::VectorXd cached_c_;
  mutable std::vector<TorqueJetAt> cached_;
  mutable std::vector<bool> cached_at_;
};

/// The plan on a dense grid: per time the reserve deficit (N) and the bounds' excess, and their worst.
struct GridViolations {
  std::vector<double> deficit_N, excess;
  double worst_deficit_N = 0.0, worst_excess = 0.0;
};

GridViolations check_grid(const SosSetup& setup, const FlatOutputMap& flat, const JointPath& path,
                          const Eigen::VectorXd& theta, const Eigen::VectorXd& reserves, const Eigen::VectorXd& a_min,
                          int points);

/// Appends the times (grid of v.size() points over [0, T]) where v is a local maximum above `tolerance`.
void local_maxima(const std::vector<double>& v, double T, double tolerance, std::vector<double>& times);

}  // namespace flatsos::planner::detail
