#pragma once
// Clamped B-splines on [0, T]: degree k, `spans` uniform knot spans, spans + k coefficients,
// C^(k-1) at the interior knots, each basis function nonzero on at most k + 1 spans. The rich,
// well-conditioned basis for flat outputs (a cubic is C2: the excitation needs Y''): a
// coefficient changes the function only locally, and on each span the spline is a polynomial of
// the span's scaled time s in [0, 1], which the SOS machinery certifies per span.
// Clamped: the value at 0 is the first coefficient, the value at T the last.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <vector>

#include <Eigen/Core>

namespace flatsos::planner {

class BSplineBasis {
 public:
  /// Throws std::invalid_argument for degree < 1, spans < 1 or a duration not > 0.
  BSplineBasis(int degree, int spans, double duration_s);

  int degree() const { return degree_; }
  int spans() const { return spans_; }
  int size() const { return spans_ + degree_; }  ///< number of coefficients
  double duration() const { return duration_s_; }
  double spanLength() const { return duration_s_ / spans_; }
  /// The span holding t (t clamped to [0, T]; T belongs to the last span).
  int spanAt(double t) const;

  /// d^order/dt^order of every basis function at t: a row of size() entries (at most
  /// degree + 1 nonzero). Order above the degree gives zeros.
  Eigen::RowVectorXd derivativeRow(double t, int order) const;
  /// On span i, the spline's coefficients in powers of the span's scaled time s = (t - t_i) / h:
  /// (degree + 1) x size() matrix M, power coefficients = M * c.
  const Eigen::MatrixXd& spanPowerMatrix(int span) const { return span_power_.at(static_cast<std::size_t>(span)); }

 private:
  int degree_, spans_;
  double duration_s_;
  std::vector<Eigen::MatrixXd> span_power_;
};

}  // namespace flatsos::planner
