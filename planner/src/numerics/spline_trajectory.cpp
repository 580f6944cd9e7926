#include "flatsos/planner/numerics/spline_trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <stdexcept>
#include <utility>

#include <Eigen/QR>

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

SplineTrajectory SplineTrajectory::inBasis(const BSplineBasis& finer) const {
  if (std::abs(finer.duration() - duration()) > 1e-12 * duration())
    throw std::invalid_argument("spline trajectory: the finer basis lasts " + std::to_string(finer.duration()) +
                                " s, the signals " + std::to_string(duration()) + " s");
  // degree + 1 points inside every span of finer determine its coefficients; a least-squares fit
  // over them is exact when the signals are among its splines, and shows when they are not.
  const int per_span = finer.degree() + 1;
  const Eigen::Index points = static_cast<Eigen::Index>(finer.spans()) * per_span;
  Eigen::MatrixXd B(points, finer.size()), values(points, coefficients_.rows());
  Eigen::Index row = 0;
  for (int span = 0; span < finer.spans(); ++span)
    for (int k = 0; k < per_span; ++k, ++row) {
      const double t = finer.spanStart(span) + finer.spanLength(span) * (k + 0.5) / per_span;
      B.row(row) = finer.derivativeRow(t, 0);
      values.row(row) = jet(t, 1).col(0).transpose();
    }
  Eigen::MatrixXd refined = B.colPivHouseholderQr().solve(values).transpose();
  const double miss = (B * refined.transpose() - values).cwiseAbs().maxCoeff();
  if (!(miss <= 1e-9 * (1.0 + values.cwiseAbs().maxCoeff())))
    throw std::invalid_argument("spline trajectory: the signals are not splines of the finer basis (they miss its fit by " +
                                std::to_string(miss) + ")");
  return SplineTrajectory(finer, std::move(refined));
}

}  // namespace flatsos::planner
