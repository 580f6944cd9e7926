#pragma once
// Clamped B-splines on [0, T]: degree k, `spans` knot spans (uniform, or between given
// breakpoints), spans + k coefficients, C^(k-1) at the interior knots, each basis function
// nonzero on at most k + 1 spans. The rich, well-conditioned basis for flat outputs (a cubic is
// C2: the excitation needs Y''): a coefficient changes the function only locally, and on each span
// the spline is a polynomial of the span's scaled time s in [0, 1], which the SOS machinery
// certifies per span. Clamped: the value at 0 is the first coefficient, the value at T the last.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <vector>

#include <Eigen/Core>

namespace flatsos::planner {

/// Breakpoints 0 = t_0 < ... < t_spans = duration_s of spans in geometric progression, each
/// `growth` times as long as the one before (exactly duration_s k / spans for growth 1). Throws
/// std::invalid_argument for spans < 1, a duration not > 0 or a growth not finite and > 0.
std::vector<double> geometric_breakpoints(int spans, double duration_s, double growth);

class BSplineBasis {
 public:
  /// Uniform spans. Throws std::invalid_argument for degree < 1, spans < 1 or a duration not > 0.
  BSplineBasis(int degree, int spans, double duration_s);
  /// Spans between breakpoints 0 = t_0 < t_1 < ... < t_S = T (s): knots where the signal changes
  /// fast. Throws std::invalid_argument for degree < 1, fewer than 2 breakpoints, a first one
  /// other than 0, or breakpoints that are not finite and strictly increasing.
  BSplineBasis(int degree, std::vector<double> breakpoints_s);
  /// Spans in geometric progression: each `growth` times as long as the one before (1: uniform;
  /// above 1 short spans at t = 0, below 1 at T). Throws std::invalid_argument for a growth that
  /// is not finite and > 0, and as the constructors.
  static BSplineBasis geometric(int degree, int spans, double duration_s, double growth);

  int degree() const { return degree_; }
  int spans() const { return spans_; }
  int size() const { return spans_ + degree_; }  ///< number of coefficients
  double duration() const { return duration_s_; }
  bool uniform() const { return uniform_; }
  double spanStart(int span) const { return breaks_[static_cast<std::size_t>(span)]; }
  double spanLength(int span) const { return breaks_[static_cast<std::size_t>(span) + 1] - spanStart(span); }
  /// t_0 .. t_S (s).
  const std::vector<double>& breakpoints() const { return breaks_; }
  /// `per_span` evenly spaced times on every span, from each span's start (T not included): where
  /// short spans get points of their own.
  std::vector<double> pointsPerSpan(int per_span) const;
  /// The span holding t (t clamped to [0, T]; T belongs to the last span).
  int spanAt(double t) const;
  /// The span's scaled time of t: (t - t_i) / h_i, clamped to [0, 1].
  double scaledTime(double t, int span) const;

  /// d^order/dt^order of every basis function at t: a row of size() entries (at most
  /// degree + 1 nonzero). Order above the degree gives zeros.
  Eigen::RowVectorXd derivativeRow(double t, int order) const;
  /// On span i, the spline's coefficients in powers of the span's scaled time s = (t - t_i) / h:
  /// (degree + 1) x size() matrix M, power coefficients = M * c.
  const Eigen::MatrixXd& spanPowerMatrix(int span) const { return span_power_.at(static_cast<std::size_t>(span)); }

 private:
  void buildSpanPowers();

  int degree_, spans_;
  double duration_s_;
  bool uniform_ = true;
  std::vector<double> breaks_;
  std::vector<Eigen::MatrixXd> span_power_;
};

}  // namespace flatsos::planner
