#pragma once
// A nonlinear effort (effort.hpp) along the free joint path, as a function of z = (theta, c): its
// Gauss-Legendre quadrature on every segment between the breakpoints of the flat outputs' and
// the path's splines; at each point and muscle the term l(F, a, n), whose F, a and n move with
// theta through the flat outputs and with c through the torque jet (pin tree, dual numbers) and
// the path lengths, a and n through the muscle inverse's exact gradients. Its value and exact
// gradient in z: the reduced-space value function (path/value_function.hpp) minimizes it over
// theta and adds its gradient in c to the rows' envelope term.

#include <Eigen/Core>
#include <vector>

#include "flatsos/planner/effort.hpp"
#include "path/path_rows.hpp"

namespace flatsos::planner::detail {

class PathEffort {
 public:
  PathEffort(const SosSetup& setup, const FlatOutputMap& flat, const PathParameterization& P,
             const Effort& effort);

  /// The points' tendon-force and path-length jets along the path of c: BoundPoints over theta
  /// (what the effort's sequential QP in theta works with).
  std::vector<BoundPoint> boundPoints(const Eigen::VectorXd& c) const;
  const std::vector<double>& weights_s() const { return weights_s_; }
  const Effort& effort() const { return effort_; }
  /// The quadrature's times (s).
  std::vector<double> times_s() const;

  /// E at z = (theta, c); false where a muscle leaves its domain or a value is not finite.
  bool value(const Eigen::VectorXd& z, double& E) const;
  /// dE/dz (z.size() entries); false as value().
  bool gradient(const Eigen::VectorXd& z, Eigen::VectorXd& g) const;

 private:
  // One muscle's term at a point: u = (F, dF, ddF, L, dL, ddL), the term and its gradient in u,
  // and u's Jacobian over the point's local variables (its theta columns, then its path columns).
  struct LocalTerm {
    Eigen::Matrix<double, 6, 1> u, gradient_u;
    MuscleEffortJet jet;
    Eigen::MatrixXd Ju;
  };
  bool localTerms(std::size_t point, const Eigen::VectorXd& z, bool gradients,
                  std::vector<LocalTerm>& terms) const;
  std::vector<int> localVariables(const PathPoint& pt) const;

  const FlatOutputMap& flat_;
  const Effort& effort_;
  int thetas_ = 0;
  std::vector<PathPoint> points_;
  std::vector<double> weights_s_;
};

}  // namespace flatsos::planner::detail
