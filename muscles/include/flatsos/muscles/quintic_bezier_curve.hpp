#pragma once
// A curve y(x) made of quintic Bezier segments laid end to end, continued by straight lines
// beyond its ends: the representation Millard et al. (2013) use for every muscle curve
// ("Flexing computational muscle: modeling and simulation of musculotendon dynamics", J Biomech
// Eng 135(2):021005; OpenSim's SmoothSegmentedFunction). Each segment is parametrised by
// u in [0, 1]: (x, y) = (X(u), Y(u)), X nondecreasing, so evaluating at x means solving X(u) = x
// first. Pure functions of their arguments; no Simbody.
//
// quintic_bezier_corner builds the segment that Millard's curve factories chain: it leaves
// (x0, y0) with slope dydx0 and arrives at (x1, y1) with slope dydx1, bending towards the
// intersection of the two end tangents. Its second derivative is 0 at both ends, so chained
// corners are C2 (not C3: the third derivative jumps at the joints and at the curve's ends).

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace flatsos::muscles {

/// One quintic Bezier segment: control points (x[i], y[i]), i = 0..5.
struct QuinticBezierSegment {
  std::array<double, 6> x{};
  std::array<double, 6> y{};
  using Samples = std::array<double, 9>;  ///< a coordinate at u = 0, 1/8, ..., 1
};

/// y and its first three derivatives in x at one point.
struct BezierCurveJet {
  double value = 0.0;
  double first = 0.0;   ///< dy/dx
  double second = 0.0;  ///< d2y/dx2
  double third = 0.0;   ///< d3y/dx3
};

/// Millard's corner: control points (P0, P0 + c (C - P0) twice, P1 + c (C - P1) twice, P1),
/// C the intersection of the end tangents (their midpoint in x when the slopes agree to within
/// sqrt(eps)). `curviness` is OpenSim's user-facing value in [0, 1]; c = 0.1 + 0.8 curviness.
/// Throws std::invalid_argument (naming `what`) if curviness is outside [0, 1], an input is not
/// finite, or C does not make a C-shaped corner (|P1 - P0| must exceed |C - P0| and |C - P1|).
QuinticBezierSegment quintic_bezier_corner(double x0, double y0, double dydx0, double x1, double y1,
                                           double dydx1, double curviness, const std::string& what);

/// A C1 curve from segments joined end to end. Inside [x_begin, x_end] it is the Bezier
/// segments; outside, the straight line with the end's value and slope (second and third
/// derivatives 0 there), as OpenSim extrapolates.
class QuinticBezierCurve {
 public:
  /// Throws std::invalid_argument (naming `name`) unless there is at least one segment, every
  /// control point is finite, each segment's x control points are nondecreasing with
  /// x[1] > x[0] and x[5] > x[4] (so dX/du > 0 on all of [0, 1]), and each segment starts where
  /// the previous one ends.
  /// The straight continuations take the Bezier's own end slopes.
  QuinticBezierCurve(std::vector<QuinticBezierSegment> segments, std::string name);
  /// The straight continuations take the given slopes, as OpenSim's factories state them (the
  /// corners' end tangents, e.g. exactly 0 for a flat end). They must equal the Bezier's end
  /// slopes to within 1e-9 (relative to max(1, |slope|)); else std::invalid_argument.
  QuinticBezierCurve(std::vector<QuinticBezierSegment> segments, std::string name,
                     double slope_begin, double slope_end);

  /// y(x). Throws std::invalid_argument if x is not finite.
  double value(double x) const;
  /// y(x) and dy/dx, d2y/dx2, d3y/dx3. Throws std::invalid_argument if x is not finite.
  BezierCurveJet evaluate(double x) const;

  /// True when y never decreases along the curve and rises on every segment (y control points
  /// nondecreasing, y[5] > y[0]): then `inverse` is defined.
  bool is_increasing() const { return increasing_; }
  /// The x with y(x) = y, for an increasing curve. Beyond the ends it inverts the straight
  /// continuation. Throws std::logic_error if the curve is not increasing, std::domain_error if
  /// y is not finite or no unique x exists (y below y(x_begin) with a flat start, or above
  /// y(x_end) with a flat end).
  double inverse(double y) const;

  double x_begin() const { return segments_.front().x[0]; }
  double x_end() const { return segments_.back().x[5]; }
  double y_begin() const { return segments_.front().y[0]; }
  double y_end() const { return segments_.back().y[5]; }
  double slope_begin() const { return slope_begin_; }  ///< dy/dx at x_begin (and before it)
  double slope_end() const { return slope_end_; }      ///< dy/dx at x_end (and after it)
  const std::vector<QuinticBezierSegment>& segments() const { return segments_; }
  const std::string& name() const { return name_; }

 private:
  std::size_t segment_index(double x) const;

  std::vector<QuinticBezierSegment> segments_;
  /// Per segment: X and Y at u = i / 8, to bracket and start the solve for u.
  std::vector<QuinticBezierSegment::Samples> x_samples_, y_samples_;
  std::string name_;
  double slope_begin_ = 0.0;
  double slope_end_ = 0.0;
  bool increasing_ = false;
};

}  // namespace flatsos::muscles
