#include "bounds/point_rows.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace flatsos::planner::detail {

PointRows::PointRows(const FlatOutputMap& flat, const std::vector<BoundPoint>& points, Eigen::VectorXd a_min, double margin)
    : flat_(flat), points_(points), a_min_(std::move(a_min)), margin_(margin) {}

void PointRows::evaluate(const Eigen::VectorXd& x, bool gradients) {
  const int m = flat_.numMuscles();
  x_ = x;
  value_.clear();
  gradient_.clear();
  activation_.clear();
  excitation_.clear();
  every_inverse_ = true;
  violation_ = 0.0;
  for (const BoundPoint& bp : points_)
    for (int j = 0; j < m; ++j) {
      const MuscleBoundRows rows = bound_rows(flat_, bp, j, a_min_[j], x, gradients, margin_);
      every_inverse_ = every_inverse_ && rows.in_domain && std::isfinite(rows.excitation);
      activation_.push_back(rows.activation);
      excitation_.push_back(rows.excitation);
      for (std::size_t k = 0; k < static_cast<std::size_t>(kRowsPerMuscle); ++k) {
        value_.push_back(rows.value[k]);
        violation_ += std::max(0.0, -rows.value[k]);
        if (gradients) gradient_.push_back(rows.gradient[k]);
      }
    }
}

bool PointRows::inverseAt(const Eigen::VectorXd& x, Eigen::MatrixXd& excitations, Eigen::MatrixXd& activations) const {
  if (!every_inverse_ || x.size() != x_.size() || x != x_) return false;
  const int m = flat_.numMuscles();
  const auto count = static_cast<Eigen::Index>(points_.size());
  excitations.resize(count, m);
  activations.resize(count, m);
  for (Eigen::Index i = 0; i < count; ++i)
    for (int j = 0; j < m; ++j) {
      const auto k = static_cast<std::size_t>(i * m + j);
      excitations(i, j) = excitation_[k];
      activations(i, j) = activation_[k];
    }
  return true;
}

void PointRows::requireGradients() const {
  if (gradient_.size() != value_.size()) throw std::logic_error("bound rows: gradients asked of rows evaluated without them");
}

void PointRows::gradient(std::size_t row, Eigen::Ref<Eigen::VectorXd> out) const {
  requireGradients();
  const auto per_point = static_cast<std::size_t>(flat_.numMuscles() * kRowsPerMuscle);
  const BoundPoint& bp = points_[row / per_point];
  const int j = static_cast<int>((row % per_point) / static_cast<std::size_t>(kRowsPerMuscle));
  out.setZero();
  for (std::size_t c = 0; c < bp.columns.size(); ++c) out[bp.columns[c]] += column_derivative(bp, gradient_[row], j, c);
}

void PointRows::change(const Eigen::VectorXd& d, std::vector<double>& out) const {
  requireGradients();
  const int m = flat_.numMuscles();
  out.resize(value_.size());
  Eigen::VectorXd d_columns;
  Eigen::MatrixXd jet_change(m, 3);  // each muscle's (F, dF, ddF) along d at the point
  std::size_t row = 0;
  for (const BoundPoint& bp : points_) {
    d_columns.resize(static_cast<Eigen::Index>(bp.columns.size()));
    for (std::size_t c = 0; c < bp.columns.size(); ++c) d_columns[static_cast<Eigen::Index>(c)] = d[bp.columns[c]];
    for (int o = 0; o < 3; ++o) jet_change.col(o).noalias() = bp.slope[static_cast<std::size_t>(o)] * d_columns;
    for (int j = 0; j < m; ++j)
      for (int k = 0; k < kRowsPerMuscle; ++k, ++row) {
        const muscles::TendonForceJetGradient& g = gradient_[row];
        out[row] = g[0] * jet_change(j, 0) + g[1] * jet_change(j, 1) + g[2] * jet_change(j, 2);
      }
  }
}

void PointRows::curvature(const std::vector<int>& rows, const Eigen::VectorXd& weight, const Eigen::VectorXd& z,
                          Eigen::VectorXd& out) const {
  out = Eigen::VectorXd::Zero(x_.size());
  const double h = curvature_step(x_, z);
  if (h == 0.0) return;
  const Eigen::VectorXd plus = x_ + h * z, minus = x_ - h * z;
  const auto per_point = static_cast<std::size_t>(flat_.numMuscles() * kRowsPerMuscle);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    // Only the row's own muscle at its own point moves with alpha: two inversions per row.
    const auto row = static_cast<std::size_t>(rows[k]);
    const BoundPoint& bp = points_[row / per_point];
    const int j = static_cast<int>((row % per_point) / static_cast<std::size_t>(kRowsPerMuscle));
    const std::size_t kind = row % static_cast<std::size_t>(kRowsPerMuscle);
    const muscles::TendonForceJetGradient g_plus = bound_rows(flat_, bp, j, a_min_[j], plus, true, margin_).gradient[kind];
    const muscles::TendonForceJetGradient g_minus = bound_rows(flat_, bp, j, a_min_[j], minus, true, margin_).gradient[kind];
    muscles::TendonForceJetGradient dg{};
    for (std::size_t o = 0; o < 3; ++o) dg[o] = weight[static_cast<Eigen::Index>(k)] * (g_plus[o] - g_minus[o]) / (2.0 * h);
    for (std::size_t c = 0; c < bp.columns.size(); ++c) out[bp.columns[c]] += column_derivative(bp, dg, j, c);
  }
}

}  // namespace flatsos::planner::detail
