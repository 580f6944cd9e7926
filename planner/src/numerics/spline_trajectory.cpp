#include "flatsos/planner/numerics/spline_trajectory.hpp"

#include <stdexcept>
#include <utility>

namespace flatsos::planner {

SplineTrajectory::SplineTrajectory(BSplineBasis basis, Eigen::MatrixXd coefficients)
    : basis_(std::move(basis)), coefficients_(std::move(coefficients)) {
  if (coefficients_.cols() != basis_.size())
    throw std::invalid_argument("spline trajectory: need " + std::to_string(basis_.size()) +
                                " coefficients per signal, got " + std::to_string(coefficients_.cols()));
  if (!coefficients_.allFinite()) throw std::invalid_argument("spline trajectory: coefficients must be finite");
}

Eigen::MatrixXd SplineTrajectory::jet(double t, int orders) const {
  Eigen::MatrixXd out(coefficients_.rows(), orders);
  for (int k = 0; k < orders; ++k) out.col(k) = coefficients_ * basis_.derivativeRow(t, k).transpose();
  return out;
}

double SplineTrajectory::derivativeAt(int row, double t, int order) const {
  return basis_.derivativeRow(t, order).dot(coefficients_.row(row));
}

Polynomial SplineTrajectory::spanPolynomial(int row, int span) const {
  return Polynomial(basis_.spanPowerMatrix(span) * coefficients_.row(row).transpose());
}

}  // namespace flatsos::planner
