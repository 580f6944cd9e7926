#pragma once
// A vector signal as clamped B-splines sharing one basis: rows of `coefficients` are the
// signals (for flat outputs, N), columns the basis functions. The paper's quartic is the
// one-span, degree-4 case (then the basis is Bernstein's).

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <vector>

#include <Eigen/Core>

#include "flatsos/planner/numerics/bspline.hpp"
#include "flatsos/planner/numerics/polynomial.hpp"

namespace flatsos::planner {

class SplineTrajectory {
 public:
  /// Throws std::invalid_argument when the coefficients do not have basis.size() columns or
  /// are not finite.
  SplineTrajectory(BSplineBasis basis, Eigen::MatrixXd coefficients);

  const BSplineBasis& basis() const { return basis_; }
  const Eigen::MatrixXd& coefficients() const { return coefficients_; }
  int signals() const { return static_cast<int>(coefficients_.rows()); }
  double duration() const { return basis_.duration(); }

  /// Derivatives 0 .. orders - 1 at t (signals x orders); t is clamped to [0, T].
  Eigen::MatrixXd jet(double t, int orders) const;
  /// The same into `out` (signals x orders, orders = its column count; allocates nothing).
  void jetInto(double t, Eigen::Ref<Eigen::MatrixXd> out) const;
  /// As jetInto inside [0, T]; beyond, the first or last span's polynomial continued, so that
  /// differences in time across an end see the signal's own motion rather than a frozen one.
  void continuedJetInto(double t, Eigen::Ref<Eigen::MatrixXd> out) const;
  /// Derivative `order` of signal `row` at t.
  double derivativeAt(int row, double t, int order = 0) const;
  /// Signal `row` on span `span` in powers of the span's scaled time s in [0, 1].
  Polynomial spanPolynomial(int row, int span) const;
  /// The same signals in `finer`, a basis whose splines include this one's (every breakpoint of
  /// this basis among finer's, a degree at least as high): exact up to rounding. Throws
  /// std::invalid_argument when the durations differ or the signals are not in finer's splines
  /// (the fit misses them by more than 1e-9 of their size).
  SplineTrajectory inBasis(const BSplineBasis& finer) const;

 private:
  void spanJetInto(int span, double s, Eigen::Ref<Eigen::MatrixXd> out) const;

  BSplineBasis basis_;
  Eigen::MatrixXd coefficients_;
  std::vector<Eigen::MatrixXd> span_powers_;  ///< per span: signals x (degree + 1), powers of s
};

}  // namespace flatsos::planner
