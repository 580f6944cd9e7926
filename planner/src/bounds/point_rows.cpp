#include "bounds/point_rows.hpp"

#include <algorithm>
#include <stdexcept>

namespace flatsos::planner::detail {

PointRows::PointRows(const FlatOutputMap& flat, const std::vector<BoundPoint>& points, Eigen::VectorXd a_min, double margin)
    : flat_(flat), points_(points), a_min_(std::move(a_min)), margin_(margin) {}

void PointRows::evaluate(const Eigen::VectorXd& x, bool gradients) {
  const int m = flat_.numMuscles();
  value_.clear();
  gradient_.clear();
  violation_ = 0.0;
  for (const BoundPoint& bp : points_)
    for (int j = 0; j < m; ++j) {
      const MuscleBoundRows rows = bound_rows(flat_, bp, j, a_min_[j], x, gradients, margin_);
      for (std::size_t k = 0; k < static_cast<std::size_t>(kRowsPerMuscle); ++k) {
        value_.push_back(rows.value[k]);
        violation_ += std::max(0.0, -rows.value[k]);
        if (gradients) gradient_.push_back(rows.gradient[k]);
      }
    }
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

}  // namespace flatsos::planner::detail
