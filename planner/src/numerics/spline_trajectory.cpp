#include "flatsos/planner/numerics/spline_trajectory.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace flatsos::planner {

SplineTrajectory::SplineTrajectory(BSplineBasis basis, Eigen::MatrixXd coefficients)
    : basis_(std::move(basis)), coefficients_(std::move(coefficients)) {
  if (coefficients_.cols() != basis_.size())
    throw std::invalid_argument("spline trajectory: need " + std::to_string(basis_.size()) +
                                " coefficients per signal, got " + std::to_string(coefficients_.cols()));
  if (!coefficients_.allFinite()) throw std::invalid_argument("spline trajectory: coefficients must be finite");
  for (int span = 0; span < basis_.spans(); ++span)
    span_powers_.push_back(coefficients_ * basis_.spanPowerMatrix(span).transpose());
}

Eigen::MatrixXd SplineTrajectory::jet(double t, int orders) const {
  Eigen::MatrixXd out(coefficients_.rows(), orders);
  jetInto(t, out);
  return out;
}

void SplineTrajectory::jetInto(double t, Eigen::Ref<Eigen::MatrixXd> out) const {
  const int span = basis_.spanAt(t);
  spanJetInto(span, basis_.scaledTime(t, span), out);
}

void SplineTrajectory::continuedJetInto(double t, Eigen::Ref<Eigen::MatrixXd> out) const {
  if (t >= 0.0 && t <= basis_.duration()) return jetInto(t, out);
  const int span = t < 0.0 ? 0 : basis_.spans() - 1;
  spanJetInto(span, (t - basis_.spanStart(span)) / basis_.spanLength(span), out);
}

void SplineTrajectory::spanJetInto(int span, double s, Eigen::Ref<Eigen::MatrixXd> out) const {
  // Horner's scheme for each derivative of the span's polynomial in s, then d/dt = (1/h) d/ds.
  const double h = basis_.spanLength(span);
  const Eigen::MatrixXd& P = span_powers_[static_cast<std::size_t>(span)];
  const int degree = basis_.degree();
  double scale = 1.0;
  for (Eigen::Index k = 0; k < out.cols(); ++k, scale /= h)
    for (Eigen::Index r = 0; r < out.rows(); ++r) {
      double v = 0.0;
      for (int p = degree; p >= k; --p) {
        double falling = 1.0;
        for (Eigen::Index q = 0; q < k; ++q) falling *= static_cast<double>(p - q);
        v = v * s + falling * P(r, p);
      }
      out(r, k) = v * scale;
    }
}

double SplineTrajectory::derivativeAt(int row, double t, int order) const {
  return basis_.derivativeRow(t, order).dot(coefficients_.row(row));
}

Polynomial SplineTrajectory::spanPolynomial(int row, int span) const {
  return Polynomial(basis_.spanPowerMatrix(span) * coefficients_.row(row).transpose());
}

}  // namespace flatsos::planner
