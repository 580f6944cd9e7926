#pragma once
// An independent restatement, for the tests, of Millard et al. (2013)'s curves (J Biomech Eng
// 135(2):021005; OpenSim's SmoothSegmentedFunctionFactory): each curve as a list of knots
// (point and slope) joined by quintic Bezier corners, the corners' control points from the
// tangent-line intersection, and the Bezier curves in Bernstein form. Nothing here calls the
// library's construction or evaluation; it takes plain numbers.
#include <array>
#include <cmath>
#include <vector>

namespace millard_reference {

struct Knot {
  double x, y, slope;
};
/// Control points of one segment: x[i], y[i].
struct ControlPoints {
  std::array<double, 6> x, y;
};

/// The corner between two knots: tangent lines P + s (1, slope) meet at C (midpoint in x if
/// the slopes are equal); inner points P0 + c (C - P0) and P1 + c (C - P1), each used twice.
inline ControlPoints corner(const Knot& a, const Knot& b, double curviness) {
  const double c = 0.1 + 0.8 * curviness;
  double cx = 0.5 * (a.x + b.x);
  if (std::abs(a.slope - b.slope) > std::sqrt(2.220446049250313e-16)) {
    const double s =
        ((b.y - a.y) - b.slope * (b.x - a.x)) / (a.slope - b.slope);  // along a's tangent
    cx = a.x + s;
  }
  const double cy = b.y + b.slope * (cx - b.x);
  const double ax = (1 - c) * a.x + c * cx, ay = (1 - c) * a.y + c * cy;
  const double bx = (1 - c) * b.x + c * cx, by = (1 - c) * b.y + c * cy;
  return {{a.x, ax, ax, bx, bx, b.x}, {a.y, ay, ay, by, by, b.y}};
}

inline std::vector<ControlPoints> chain(const std::vector<Knot>& knots,
                                        const std::vector<double>& curviness) {
  std::vector<ControlPoints> segments;
  for (std::size_t i = 0; i + 1 < knots.size(); ++i)
    segments.push_back(corner(knots[i], knots[i + 1], curviness[i]));
  return segments;
}

/// sum_i C(5, i) u^i (1 - u)^(5 - i) p_i
inline double bernstein(const std::array<double, 6>& p, double u) {
  const double binomial[6] = {1, 5, 10, 10, 5, 1};
  double sum = 0.0;
  for (int i = 0; i < 6; ++i) sum += binomial[i] * std::pow(u, i) * std::pow(1 - u, 5 - i) * p[i];
  return sum;
}

/// d/du of the Bernstein form, term by term.
inline double bernstein_derivative(const std::array<double, 6>& p, double u) {
  const double binomial[6] = {1, 5, 10, 10, 5, 1};
  double sum = 0.0;
  for (int i = 0; i < 6; ++i) {
    const double rising = i > 0 ? i * std::pow(u, i - 1) * std::pow(1 - u, 5 - i) : 0.0;
    const double falling = i < 5 ? (5 - i) * std::pow(u, i) * std::pow(1 - u, 4 - i) : 0.0;
    sum += binomial[i] * (rising - falling) * p[i];
  }
  return sum;
}

// ---- The published constructions, from the properties as numbers.

inline std::vector<ControlPoints> active_force_length(double min_length, double transition,
                                                      double max_length, double shallow_slope,
                                                      double minimum_value) {
  const double shoulder = 0.95;  // plateau widened by 0.05 optimal lengths each side of 1
  const double top = 1 - shallow_slope * (shoulder - transition);
  const double steep = 1.25 * top / (transition - min_length);
  const std::vector<Knot> knots = {{min_length, minimum_value, 0},
                                   {(min_length + transition) / 2, top / 2, steep},
                                   {(transition + shoulder) / 2, (top + 1) / 2, shallow_slope},
                                   {1, 1, 0},
                                   {(1.05 + max_length) / 2, 0.5, -1 / (max_length - 0.05 - 1.05)},
                                   {max_length, minimum_value, 0}};
  return chain(knots, {1, 1, 1, 1, 1});
}

inline std::vector<ControlPoints> force_velocity(double at_c, double near_c, double iso,
                                                 double at_e, double near_e, double f_max,
                                                 double curv_c, double curv_e) {
  const std::vector<Knot> knots = {{-1, 0, at_c},
                                   {-0.9, 0.05 * (near_c + at_c), near_c},
                                   {0, 1, iso},
                                   {0.9, f_max - 0.05 * (near_e + at_e), near_e},
                                   {1, f_max, at_e}};
  return chain(knots, {curv_c, curv_c, curv_e, curv_e});
}

inline std::vector<ControlPoints> fiber_force_length(double e0, double e1, double k_low,
                                                     double k_one, double curv) {
  const double dx = std::fmin(0.1 / k_one, 0.1 * (e1 - e0));
  const std::vector<Knot> knots = {
      {1 + e0, 0, 0}, {1 + e0 + dx, k_low * dx / 2, k_low}, {1 + e1, 1, k_one}};
  return chain(knots, {curv, curv});
}

inline std::vector<ControlPoints> tendon_force_length(double e, double k, double f_toe,
                                                      double curv) {
  const double x_toe = 1 + e - (1 - f_toe) / k;
  const double x_foot = 1 + (x_toe - 1) / 10;
  const double x_half = 1 + e - (1 - f_toe / 2) / k;  // the linear part reaches f_toe / 2 here
  const double mid_slope = (f_toe / 2) / (x_half - x_foot);
  const double x_mid = (x_foot + x_half) / 2;
  const std::vector<Knot> knots = {
      {1, 0, 0}, {x_mid, mid_slope * (x_mid - x_foot), mid_slope}, {x_toe, f_toe, k}};
  return chain(knots, {curv, curv});
}

/// From (0, 1) with slope k down to (x_zero, 0), flat there (both compressive curves).
inline std::vector<ControlPoints> compressive(double x_zero, double k, double curv) {
  return chain({{0, 1, k}, {x_zero, 0, 0}}, {curv});
}

}  // namespace millard_reference
