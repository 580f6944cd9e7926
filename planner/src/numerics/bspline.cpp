#include "flatsos/planner/numerics/bspline.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "flatsos/planner/numerics/polynomial.hpp"

namespace flatsos::planner {

namespace {

// Clamped knot vector in units of spans: k + 1 zeros, 1 .. spans - 1, k + 1 times `spans`.
std::vector<double> clamped_knots(int k, int spans) {
  std::vector<double> u(static_cast<std::size_t>(k + 1), 0.0);
  for (int i = 1; i < spans; ++i) u.push_back(i);
  u.insert(u.end(), static_cast<std::size_t>(k + 1), static_cast<double>(spans));
  return u;
}

// Cox-de Boor: the k + 1 basis values nonzero on span `span` at x (knot units), for functions
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
  const std::vector<double> u = clamped_knots(degree, spans);
  // Each nonzero basis function on a span is a polynomial of degree k: interpolate its values
  // at k + 1 Chebyshev points of the span (exact up to rounding, well conditioned).
  const Eigen::VectorXd nodes = chebyshev_nodes_unit_interval(degree + 1);
  for (int span = 0; span < spans; ++span) {
    Eigen::MatrixXd values(degree + 1, degree + 1);  // node x local function
    for (int n = 0; n < nodes.size(); ++n) values.row(n) = nonzero_basis(u, degree, span, span + nodes[n]).transpose();
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(degree + 1, size());
    for (int f = 0; f <= degree; ++f) M.col(span + f) = interpolating_polynomial(nodes, values.col(f)).coefficients();
    span_power_.push_back(std::move(M));
  }
}

int BSplineBasis::spanAt(double t) const {
  const double x = std::clamp(t / duration_s_, 0.0, 1.0) * spans_;
  return std::min(static_cast<int>(std::floor(x)), spans_ - 1);
}

Eigen::RowVectorXd BSplineBasis::derivativeRow(double t, int order) const {
  const int span = spanAt(t);
  const double h = spanLength();
  const double s = std::clamp(t / h - span, 0.0, 1.0);
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
