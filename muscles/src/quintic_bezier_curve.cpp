// Segmented quintic Bezier curves (Millard et al. 2013, J Biomech Eng 135(2):021005).
// A segment is evaluated by de Casteljau's algorithm on its control points and on those of its
// derivative curves (the hodographs), so no power-basis coefficients with cancellation appear.
#include "flatsos/muscles/quintic_bezier_curve.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace flatsos::muscles {
namespace {

constexpr double kMachineEpsilon = std::numeric_limits<double>::epsilon();

template <std::size_t N>
double de_casteljau(std::array<double, N> points, double u) {
  for (std::size_t level = N - 1; level > 0; --level) {
    for (std::size_t i = 0; i < level; ++i) points[i] += u * (points[i + 1] - points[i]);
  }
  return points[0];
}

/// Control points of the derivative in u of a Bezier curve of degree N - 1.
template <std::size_t N>
std::array<double, N - 1> hodograph(const std::array<double, N>& points) {
  std::array<double, N - 1> derivative{};
  for (std::size_t i = 0; i + 1 < N; ++i)
    derivative[i] = double(N - 1) * (points[i + 1] - points[i]);
  return derivative;
}

/// One coordinate of a segment and its first three derivatives in u.
struct ParameterJet {
  double value, first, second, third;
};

ParameterJet parameter_jet(const std::array<double, 6>& points, double u) {
  const auto d1 = hodograph(points);
  const auto d2 = hodograph(d1);
  const auto d3 = hodograph(d2);
  return {de_casteljau(points, u), de_casteljau(d1, u), de_casteljau(d2, u), de_casteljau(d3, u)};
}

using Samples = QuinticBezierSegment::Samples;

Samples sample(const std::array<double, 6>& points) {
  Samples samples{};
  const std::size_t intervals = samples.size() - 1;
  for (std::size_t i = 0; i <= intervals; ++i)
    samples[i] = de_casteljau(points, double(i) / double(intervals));
  return samples;
}

/// The u in [0, 1] with B(u) = target for nondecreasing control points (B nondecreasing).
/// The samples of B bracket the root and give a first guess by linear interpolation; Newton's
/// method then stays inside the shrinking bracket, bisecting whenever a step would leave it,
/// and stops when u moves by at most 2 eps, i.e. u is as exact as a double allows.
double solve_parameter(const std::array<double, 6>& points, const Samples& samples, double target) {
  if (target <= points[0]) return 0.0;
  if (target >= points[5]) return 1.0;
  const std::size_t intervals = samples.size() - 1;
  std::size_t i = 0;
  while (i + 1 < intervals && target >= samples[i + 1]) ++i;
  double lower = double(i) / double(intervals), upper = double(i + 1) / double(intervals);
  const double rise = samples[i + 1] - samples[i];
  double u =
      rise > 0.0 ? lower + (upper - lower) * (target - samples[i]) / rise : 0.5 * (lower + upper);
  const auto slope_points = hodograph(points);
  for (int iteration = 0; iteration < 200; ++iteration) {
    const double residual = de_casteljau(points, u) - target;
    if (residual == 0.0) return u;
    (residual < 0.0 ? lower : upper) = u;
    const double slope = de_casteljau(slope_points, u);
    double next = slope > 0.0 ? u - residual / slope : lower;
    if (!(next > lower && next < upper)) next = 0.5 * (lower + upper);
    if (std::abs(next - u) <= 2.0 * kMachineEpsilon) return next;
    u = next;
  }
  return u;
}

/// Derivatives of y in x from those of x and y in u (chain rule; x' > 0).
BezierCurveJet jet_in_x(const ParameterJet& x, const ParameterJet& y) {
  const double inverse_speed = 1.0 / x.first;
  const double bend = y.second * x.first - y.first * x.second;  // x'^3 d2y/dx2
  const double bend_rate = y.third * x.first - y.first * x.third;
  const double speed2 = x.first * x.first;
  return {y.value, y.first * inverse_speed, bend * inverse_speed / speed2,
          (bend_rate * x.first - 3.0 * x.second * bend) / (speed2 * speed2 * x.first)};
}

[[noreturn]] void reject_curve(const std::string& name, const std::string& problem) {
  throw std::invalid_argument("quintic Bezier curve '" + name + "': " + problem);
}

void check_segment(const QuinticBezierSegment& segment, std::size_t index,
                   const std::string& name) {
  std::ostringstream where;
  where << "segment " << index << ": ";
  for (std::size_t i = 0; i < 6; ++i) {
    if (!std::isfinite(segment.x[i]) || !std::isfinite(segment.y[i])) {
      reject_curve(name, where.str() + "control points must be finite");
    }
    if (i > 0 && segment.x[i] < segment.x[i - 1]) {
      reject_curve(name, where.str() + "x control points must be nondecreasing");
    }
  }
  if (!(segment.x[1] > segment.x[0] && segment.x[5] > segment.x[4])) {
    reject_curve(name, where.str() + "x must rise at both ends (x[1] > x[0], x[5] > x[4])");
  }
}

bool joins(double end, double start) {
  return std::abs(end - start) <= 64.0 * kMachineEpsilon * std::max({1.0, std::abs(end), std::abs(start)});
}

bool rises(const QuinticBezierSegment& segment) {
  for (std::size_t i = 1; i < 6; ++i) {
    if (segment.y[i] < segment.y[i - 1]) return false;
  }
  return segment.y[5] > segment.y[0];
}

}  // namespace

QuinticBezierSegment quintic_bezier_corner(double x0, double y0, double dydx0, double x1, double y1,
                                           double dydx1, double curviness,
                                           const std::string& what) {
  for (double input : {x0, y0, dydx0, x1, y1, dydx1, curviness}) {
    if (!std::isfinite(input)) throw std::invalid_argument(what + ": corner inputs must be finite");
  }
  if (curviness < 0.0 || curviness > 1.0) {
    throw std::invalid_argument(what + ": curviness must be in [0, 1]");
  }
  const double c = 0.1 + 0.8 * curviness;
  const double corner_x = std::abs(dydx0 - dydx1) > std::sqrt(kMachineEpsilon)
                              ? (y1 - y0 - x1 * dydx1 + x0 * dydx0) / (dydx0 - dydx1)
                              : 0.5 * (x0 + x1);
  const double corner_y = y1 + (corner_x - x1) * dydx1;
  const auto squared_distance = [](double ax, double ay, double bx, double by) {
    return (ax - bx) * (ax - bx) + (ay - by) * (ay - by);
  };
  const double chord = squared_distance(x0, y0, x1, y1);
  if (!(chord > squared_distance(corner_x, corner_y, x0, y0) &&
        chord > squared_distance(corner_x, corner_y, x1, y1))) {
    throw std::invalid_argument(what + ": the end tangents do not meet in a C-shaped corner");
  }
  const double x0_inner = x0 + c * (corner_x - x0), y0_inner = y0 + c * (corner_y - y0);
  const double x1_inner = x1 + c * (corner_x - x1), y1_inner = y1 + c * (corner_y - y1);
  return {{x0, x0_inner, x0_inner, x1_inner, x1_inner, x1},
          {y0, y0_inner, y0_inner, y1_inner, y1_inner, y1}};
}

QuinticBezierCurve::QuinticBezierCurve(std::vector<QuinticBezierSegment> segments, std::string name)
    : segments_(std::move(segments)), name_(std::move(name)) {
  if (segments_.empty()) reject_curve(name_, "needs at least one segment");
  increasing_ = true;
  for (std::size_t i = 0; i < segments_.size(); ++i) {
    check_segment(segments_[i], i, name_);
    if (i > 0 && !(joins(segments_[i - 1].x[5], segments_[i].x[0]) &&
                   joins(segments_[i - 1].y[5], segments_[i].y[0]))) {
      reject_curve(name_,
                   "segment " + std::to_string(i) + " does not start where the previous one ends");
    }
    increasing_ = increasing_ && rises(segments_[i]);
    x_samples_.push_back(sample(segments_[i].x));
    y_samples_.push_back(sample(segments_[i].y));
  }
  const QuinticBezierSegment& first = segments_.front();
  const QuinticBezierSegment& last = segments_.back();
  slope_begin_ = (first.y[1] - first.y[0]) / (first.x[1] - first.x[0]);
  slope_end_ = (last.y[5] - last.y[4]) / (last.x[5] - last.x[4]);
}

QuinticBezierCurve::QuinticBezierCurve(std::vector<QuinticBezierSegment> segments, std::string name,
                                       double slope_begin, double slope_end)
    : QuinticBezierCurve(std::move(segments), std::move(name)) {
  const auto close = [](double stated, double own) {
    return std::abs(stated - own) <= 1e-9 * std::max(1.0, std::abs(own));
  };
  if (!close(slope_begin, slope_begin_) || !close(slope_end, slope_end_)) {
    reject_curve(name_, "the stated end slopes differ from the Bezier's own");
  }
  slope_begin_ = slope_begin;
  slope_end_ = slope_end;
}

std::size_t QuinticBezierCurve::segment_index(double x) const {
  // A joint belongs to the segment that starts there, as in OpenSim.
  for (std::size_t i = 0; i + 1 < segments_.size(); ++i) {
    if (x < segments_[i].x[5]) return i;
  }
  return segments_.size() - 1;
}

double QuinticBezierCurve::value(double x) const { return evaluate(x).value; }

BezierCurveJet QuinticBezierCurve::evaluate(double x) const {
  if (!std::isfinite(x)) reject_curve(name_, "x must be finite");
  if (x < x_begin()) return {y_begin() + slope_begin_ * (x - x_begin()), slope_begin_, 0.0, 0.0};
  if (x > x_end()) return {y_end() + slope_end_ * (x - x_end()), slope_end_, 0.0, 0.0};
  const std::size_t index = segment_index(x);
  const QuinticBezierSegment& segment = segments_[index];
  const double u = solve_parameter(segment.x, x_samples_[index], x);
  return jet_in_x(parameter_jet(segment.x, u), parameter_jet(segment.y, u));
}

double QuinticBezierCurve::inverse(double y) const {
  if (!increasing_)
    throw std::logic_error("quintic Bezier curve '" + name_ + "' is not increasing: no inverse");
  if (!std::isfinite(y))
    throw std::domain_error("quintic Bezier curve '" + name_ + "': y must be finite");
  const auto no_unique_x = [&] {
    std::ostringstream message;
    message << "quintic Bezier curve '" << name_ << "': no unique x has y = " << y
            << " (range of the curve: ";
    message << (slope_begin_ > 0.0 ? "-inf" : std::to_string(y_begin())) << " to ";
    message << (slope_end_ > 0.0 ? "+inf" : std::to_string(y_end()))
            << ", ends excluded where flat)";
    return std::domain_error(message.str());
  };
  if (y <= y_begin() && slope_begin_ <= 0.0) throw no_unique_x();
  if (y >= y_end() && slope_end_ <= 0.0) throw no_unique_x();
  if (y < y_begin()) return x_begin() + (y - y_begin()) / slope_begin_;
  if (y > y_end()) return x_end() + (y - y_end()) / slope_end_;
  std::size_t index = 0;
  while (index + 1 < segments_.size() && y > segments_[index].y[5]) ++index;
  const QuinticBezierSegment& segment = segments_[index];
  return de_casteljau(segment.x, solve_parameter(segment.y, y_samples_[index], y));
}

}  // namespace flatsos::muscles
