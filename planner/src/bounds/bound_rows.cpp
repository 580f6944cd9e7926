#include "bounds/bound_rows.hpp"

#include <algorithm>
#include <cmath>

namespace flatsos::planner::detail {

namespace fm = flatsos::muscles;

Eigen::VectorXd activation_minima(const FlatOutputMap& flat, double min_activation) {
  Eigen::VectorXd a_min(flat.numMuscles());
  for (int j = 0; j < flat.numMuscles(); ++j)
    a_min[j] = min_activation > 0.0 ? min_activation : flat.model().muscle(j).getParameters().activation_floor;
  return a_min;
}

CompressedRow compress_row(double r) {
  if (std::abs(r) <= 1.0) return {r, 1.0};
  return {std::copysign(1.0 + std::log(std::abs(r)), r), 1.0 / std::abs(r)};
}

MuscleBoundRows muscle_bound_rows(const fm::MuscleParameters& p, const fm::SecondOrderJet& force,
                                  const fm::SecondOrderJet& path, double a_min, bool gradients, double margin) {
  return muscle_bound_rows(p, force, path, a_min,
                           gradients ? fm::InverseGradients::ForceAndPathJets : fm::InverseGradients::None, margin);
}

MuscleBoundRows muscle_bound_rows(const fm::MuscleParameters& p, const fm::SecondOrderJet& force,
                                  const fm::SecondOrderJet& path, double a_min, fm::InverseGradients which,
                                  double margin) {
  const bool gradients = which != fm::InverseGradients::None;
  const fm::MuscleInverse inv = fm::invert_muscle(p, force, path, which);
  MuscleBoundRows rows;
  if (inv.stage != fm::MuscleInverse::Stage::Complete) {
    rows.value.fill(-(kOutsideDomain + inv.domain_distance));
    for (std::size_t k = 0; k < rows.value.size(); ++k)
      for (std::size_t o = 0; o < 3; ++o) {
        rows.gradient[k][o] = -inv.domain_distance_gradient[o];
        rows.path_gradient[k][o] = -inv.path_domain_distance_gradient[o];
      }
    return rows;
  }
  rows.in_domain = true;
  rows.activation = inv.activation;
  rows.excitation = inv.excitation;
  const fm::ExcitationBoundMargins m = fm::excitation_bound_margins(p, inv.activation, inv.activation_rate_per_s);
  // Imposed with a margin (kBoundMargin at least) wider than the step LPs resolve rows (about
  // 4e-7 with Clp's scaling), so that a row met to that resolution still leaves the plan inside.
  const std::array<double, kRowsPerMuscle> raw = {inv.activation - a_min - margin, 1.0 - inv.activation - margin,
                                                  m.lower - margin, m.upper - margin};
  std::array<double, kRowsPerMuscle> slope{};
  for (std::size_t k = 0; k < raw.size(); ++k) {
    const CompressedRow c = compress_row(raw[k]);
    rows.value[k] = c.value;
    slope[k] = c.slope;
  }
  if (gradients)
    for (std::size_t o = 0; o < 3; ++o) {
      const double da = inv.activation_gradient[o], dadot = inv.activation_rate_gradient[o];
      rows.gradient[0][o] = slope[0] * da;
      rows.gradient[1][o] = -slope[1] * da;
      rows.gradient[2][o] = slope[2] * (m.lower_d_activation * da + m.lower_d_rate_s * dadot);
      rows.gradient[3][o] = slope[3] * (m.upper_d_activation * da + m.upper_d_rate_s * dadot);
      const double pa = inv.path_activation_gradient[o], padot = inv.path_activation_rate_gradient[o];
      rows.path_gradient[0][o] = slope[0] * pa;
      rows.path_gradient[1][o] = -slope[1] * pa;
      rows.path_gradient[2][o] = slope[2] * (m.lower_d_activation * pa + m.lower_d_rate_s * padot);
      rows.path_gradient[3][o] = slope[3] * (m.upper_d_activation * pa + m.upper_d_rate_s * padot);
    }
  return rows;
}

fm::SecondOrderJet point_force_jet(const BoundPoint& bp, int j, const Eigen::Ref<const Eigen::VectorXd>& theta) {
  double F[3];
  for (int k = 0; k < 3; ++k) {
    double v = bp.base(j, k);
    const auto& s = bp.slope[static_cast<std::size_t>(k)];
    for (std::size_t c = 0; c < bp.columns.size(); ++c) v += s(j, static_cast<Eigen::Index>(c)) * theta[bp.columns[c]];
    F[k] = v;
  }
  return {F[0], F[1], F[2]};
}

MuscleBoundRows bound_rows(const FlatOutputMap& flat, const BoundPoint& bp, int j, double a_min,
                           const Eigen::Ref<const Eigen::VectorXd>& theta, bool gradients, double margin) {
  return muscle_bound_rows(flat.model().muscle(j).getParameters(), point_force_jet(bp, j, theta),
                           bp.path[static_cast<std::size_t>(j)], a_min,
                           gradients ? fm::InverseGradients::ForceJet : fm::InverseGradients::None, margin);
}

bool point_excitations(const FlatOutputMap& flat, const std::vector<BoundPoint>& points, const Eigen::VectorXd& theta,
                       Eigen::MatrixXd& excitations, Eigen::MatrixXd& activations) {
  const int m = flat.numMuscles();
  const auto count = static_cast<Eigen::Index>(points.size());
  excitations.resize(count, m);
  activations.resize(count, m);
  for (Eigen::Index i = 0; i < count; ++i) {
    const BoundPoint& bp = points[static_cast<std::size_t>(i)];
    for (int j = 0; j < m; ++j) {
      const fm::MuscleInverse inv = fm::invert_muscle(flat.model().muscle(j).getParameters(), point_force_jet(bp, j, theta),
                                                      bp.path[static_cast<std::size_t>(j)], false);
      if (inv.stage != fm::MuscleInverse::Stage::Complete || !std::isfinite(inv.excitation)) return false;
      excitations(i, j) = inv.excitation;
      activations(i, j) = inv.activation;
    }
  }
  return true;
}

double column_derivative(const BoundPoint& bp, const fm::TendonForceJetGradient& g, int j, std::size_t c) {
  double v = 0.0;
  for (std::size_t o = 0; o < 3; ++o) v += g[o] * bp.slope[o](j, static_cast<Eigen::Index>(c));
  return v;
}

BoundRowsAt evaluate_rows(const FlatOutputMap& flat, const std::vector<BoundPoint>& points, const Eigen::VectorXd& a_min,
                          const Eigen::VectorXd& theta, bool jacobian, double margin) {
  BoundRowsAt out;
  append_rows(flat, points, 0, a_min, theta, jacobian, margin, out);
  return out;
}

void append_rows(const FlatOutputMap& flat, const std::vector<BoundPoint>& points, std::size_t first_point,
                 const Eigen::VectorXd& a_min, const Eigen::VectorXd& theta, bool jacobian, double margin,
                 BoundRowsAt& out) {
  const int m = flat.numMuscles();
  const auto per_point = static_cast<std::size_t>(m * kRowsPerMuscle);
  out.value.reserve(points.size() * per_point);
  if (jacobian) {
    std::size_t entries = out.jacobian.size();
    for (std::size_t k = first_point; k < points.size(); ++k) entries += points[k].columns.size() * per_point;
    out.jacobian.reserve(entries);
  }
  auto row = static_cast<int>(out.value.size());
  for (std::size_t point = first_point; point < points.size(); ++point) {
    const BoundPoint& bp = points[point];
    for (int j = 0; j < m; ++j) {
      const MuscleBoundRows rows = bound_rows(flat, bp, j, a_min[j], theta, jacobian, margin);
      for (int k = 0; k < kRowsPerMuscle; ++k, ++row) {
        out.value.push_back(rows.value[static_cast<std::size_t>(k)]);
        out.violation += std::max(0.0, -rows.value[static_cast<std::size_t>(k)]);
        if (jacobian)
          for (std::size_t c = 0; c < bp.columns.size(); ++c)
            out.jacobian.emplace_back(row, bp.columns[c], column_derivative(bp, rows.gradient[static_cast<std::size_t>(k)], j, c));
      }
    }
  }
}

JacobianByRow::JacobianByRow(const BoundRowsAt& rows) : start_(rows.value.size() + 1, 0) {
  for (const auto& t : rows.jacobian) ++start_[static_cast<std::size_t>(t.row()) + 1];
  for (std::size_t i = 1; i < start_.size(); ++i) start_[i] += start_[i - 1];
  column_.resize(rows.jacobian.size());
  value_.resize(rows.jacobian.size());
  std::vector<int> next(start_.begin(), start_.end() - 1);
  for (const auto& t : rows.jacobian) {
    const auto k = static_cast<std::size_t>(next[static_cast<std::size_t>(t.row())]++);
    column_[k] = t.col();
    value_[k] = t.value();
  }
  l1_.assign(rows.value.size(), 0.0);
  for (std::size_t i = 0; i < l1_.size(); ++i)
    for (int k = start_[i]; k < start_[i + 1]; ++k) l1_[i] += std::abs(value_[static_cast<std::size_t>(k)]);
}

void JacobianByRow::append_row(std::size_t row, int lp_row, std::vector<Eigen::Triplet<double>>& entries) const {
  for (int k = start_[row]; k < start_[row + 1]; ++k)
    entries.emplace_back(lp_row, column_[static_cast<std::size_t>(k)], value_[static_cast<std::size_t>(k)]);
}

void JacobianByRow::copy_row(std::size_t row, Eigen::Ref<Eigen::VectorXd> out) const {
  out.setZero();
  for (int k = start_[row]; k < start_[row + 1]; ++k) out[column_[static_cast<std::size_t>(k)]] += value_[static_cast<std::size_t>(k)];
}

double reserve_violation_N(const LinearProgram& lp, const Eigen::VectorXd& theta) {
  if (lp.G.rows() == 0) return 0.0;
  return (lp.row_lower - lp.G * theta).cwiseMax(0.0).sum();
}

}  // namespace flatsos::planner::detail
