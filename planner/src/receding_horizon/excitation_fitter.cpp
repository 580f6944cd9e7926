#include "flatsos/planner/excitation_fitter.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/QR>

namespace flatsos::planner {

namespace {
Eigen::MatrixXd vandermonde(int samples, int degree) {
  Eigen::MatrixXd V(samples, degree + 1);
  for (int i = 0; i < samples; ++i)
    for (int k = 0; k <= degree; ++k) V(i, k) = std::pow(static_cast<double>(i) / (samples - 1), k);
  return V;
}
}  // namespace

ExcitationFitter::ExcitationFitter(int samples, double period_s) : samples_(samples), period_s_(period_s) {
  if (samples < 2) throw std::invalid_argument("RH controller: need at least 2 excitation samples per period");
  if (!(period_s > 0.0) || !std::isfinite(period_s)) throw std::invalid_argument("RH controller: control period must be > 0 s");
  // The least-squares solution of V c = samples for every right-hand side at once, by the
  // column-pivoting QR (V is well conditioned on [0, 1] at these degrees).
  const Eigen::MatrixXd V = vandermonde(samples, std::min(samples - 1, kMaxDegree));
  solution_operator_ = V.colPivHouseholderQr().solve(Eigen::MatrixXd::Identity(samples, samples));
}

plugin::ExcitationPolynomial ExcitationFitter::fit(const Eigen::Ref<const Eigen::VectorXd>& values, double t0_s) const {
  if (values.size() != samples_) throw std::invalid_argument("excitation fit: wrong number of samples");
  plugin::ExcitationPolynomial piece;
  piece.count = static_cast<int>(solution_operator_.rows());
  Eigen::Map<Eigen::VectorXd>(piece.coefficients.data(), piece.count).noalias() = solution_operator_ * values;
  piece.start_time_s = t0_s;
  piece.duration_s = period_s_;
  return piece;
}

}  // namespace flatsos::planner
