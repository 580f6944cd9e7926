#include "flatsos/planner/numerics/bspline.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "flatsos/planner/numerics/polynomial.hpp"

namespace flatsos::planner {

namespace {

// Clamped knot vector (s): k + 1 zeros, the interior breakpoints, k + 1 times T.
std::vector<double> clamped_knots(int k, const std::vector<double>& breaks) {
  std::vector<double> u(static_cast<std::size_t>(k + 1), 0.0);
  u.insert(u.end(), breaks.begin() + 1, breaks.end() - 1);
  u.insert(u.end(), static_cast<std::size_t>(k + 1), breaks.back());
  return u;
}

// Cox-de Boor: the k + 1 basis values nonzero on span `span` at x (s), for functions
// span .. span + k.
Eigen::VectorXd nonzero_basis(const std::vector<double>& u, int k, int span, double x) {
  const int i = span + k;  // u[i] <= x < u[i + 1]
  Eigen::VectorXd N = Eigen::VectorXd::Zero(k + 1), left(k + 1), right(k + 1);
  N[0] = 1.0;
  for (int j = 1; j <= k; ++j) {
    left[j] = x - u[static_cast<std::size_t>(i + 1 - j)];
    right[j] = u[static_cast<std::size_t>(i + j)] - x;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      const double temp = N[r] / (right[r + 1] + left[j - r]);
      N[r] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    N[j] = saved;
  }
  return N;
}

}  // namespace

BSplineBasis::BSplineBasis(int degree, int spans, double duration_s) : degree_(degree), spans_(spans), duration_s_(duration_s) {
  if (degree < 1) throw std::invalid_argument("B-spline basis: degree must be >= 1");
  if (spans < 1) throw std::invalid_argument("B-spline basis: need at least 1 span");
  if (!(duration_s > 0.0) || !std::isfinite(duration_s)) throw std::invalid_argument("B-spline basis: duration must be > 0 s");
  const double h = duration_s / spans;
  for (int i = 0; i < spans; ++i) breaks_.push_back(i * h);
  breaks_.push_back(duration_s);
  buildSpanPowers();
}

BSplineBasis::BSplineBasis(int degree, std::vector<double> breakpoints_s)
    : degree_(degree), spans_(static_cast<int>(breakpoints_s.size()) - 1), duration_s_(0.0), uniform_(false),
      breaks_(std::move(breakpoints_s)) {
  if (degree < 1) throw std::invalid_argument("B-spline basis: degree must be >= 1");
  if (breaks_.size() < 2) throw std::invalid_argument("B-spline basis: need at least 2 breakpoints (1 span)");
  if (breaks_.front() != 0.0) throw std::invalid_argument("B-spline basis: the first breakpoint must be 0 s");
  for (std::size_t i = 1; i < breaks_.size(); ++i)
    if (!std::isfinite(breaks_[i]) || !(breaks_[i] > breaks_[i - 1]))
      throw std::invalid_argument("B-spline basis: breakpoint " + std::to_string(i) +
                                  " is not finite or not above the one before");
  duration_s_ = breaks_.back();
  buildSpanPowers();
}

std::vector<double> geometric_breakpoints(int spans, double duration_s, double growth) {
  if (spans < 1) throw std::invalid_argument("B-spline basis: need at least 1 span");
  if (!(duration_s > 0.0) || !std::isfinite(duration_s)) throw std::invalid_argument("B-spline basis: duration must be > 0 s");
  if (!(growth > 0.0) || !std::isfinite(growth)) throw std::invalid_argument("B-spline basis: span growth must be finite and > 0");
  std::vector<double> breaks{0.0};
  if (growth == 1.0) {
    for (int i = 1; i < spans; ++i) breaks.push_back(duration_s * i / spans);
  } else {
    // h_i = h_0 growth^i with sum h_i = T.
    const double first_s = duration_s * (growth - 1.0) / (std::pow(growth, spans) - 1.0);
    for (int i = 1; i < spans; ++i) breaks.push_back(breaks.back() + first_s * std::pow(growth, i - 1));
  }
  breaks.push_back(duration_s);
  return breaks;
}

BSplineBasis BSplineBasis::geometric(int degree, int spans, double duration_s, double growth) {
  if (growth == 1.0) return BSplineBasis(degree, spans, duration_s);  // the uniform basis' own arithmetic
  return BSplineBasis(degree, geometric_breakpoints(spans, duration_s, growth));
}

void BSplineBasis::buildSpanPowers() {
  const std::vector<double> u = clamped_knots(degree_, breaks_);
  // Each nonzero basis function on a span is a polynomial of degree k: interpolate its values
  // at k + 1 Chebyshev points of the span (exact up to rounding, well conditioned).
  const Eigen::VectorXd nodes = chebyshev_nodes_unit_interval(degree_ + 1);
  for (int span = 0; span < spans_; ++span) {
    Eigen::MatrixXd values(degree_ + 1, degree_ + 1);  // node x local function
    for (int n = 0; n < nodes.size(); ++n)
      values.row(n) = nonzero_basis(u, degree_, span, spanStart(span) + spanLength(span) * nodes[n]).transpose();
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(degree_ + 1, size());
    for (int f = 0; f <= degree_; ++f) M.col(span + f) = interpolating_polynomial(nodes, values.col(f)).coefficients();
    span_power_.push_back(std::move(M));
  }
}

std::vector<double> BSplineBasis::pointsPerSpan(int per_span) const {
  std::vector<double> times;
  for (int span = 0; span < spans_ && per_span > 0; ++span)
    for (int k = 0; k < per_span; ++k) times.push_back(spanStart(span) + spanLength(span) * k / per_span);
  return times;
}

int BSplineBasis::spanAt(double t) const {
  if (uniform_) {
    const double x = std::clamp(t / duration_s_, 0.0, 1.0) * spans_;
    return std::min(static_cast<int>(std::floor(x)), spans_ - 1);
  }
  const auto after = std::upper_bound(breaks_.begin() + 1, breaks_.end() - 1, t);
  return static_cast<int>(after - breaks_.begin()) - 1;
}

double BSplineBasis::scaledTime(double t, int span) const {
  // Uniform spans: t / h - span, exactly as the spans were always scaled.
  const double s = uniform_ ? t / spanLength(0) - span : (t - spanStart(span)) / spanLength(span);
  return std::clamp(s, 0.0, 1.0);
}

Eigen::RowVectorXd BSplineBasis::derivativeRow(double t, int order) const {
  const int span = spanAt(t);
  const double h = spanLength(span);
  const double s = scaledTime(t, span);
  // d^order/ds^order of s^p at s, then d/dt = (1/h) d/ds.
  Eigen::RowVectorXd monomial = Eigen::RowVectorXd::Zero(degree_ + 1);
  for (int p = order; p <= degree_; ++p) {
    double factor = 1.0;
    for (int q = 0; q < order; ++q) factor *= p - q;
    monomial[p] = factor * std::pow(s, p - order);
  }
  return monomial * spanPowerMatrix(span) / std::pow(h, order);
}

}  // namespace flatsos::planner
