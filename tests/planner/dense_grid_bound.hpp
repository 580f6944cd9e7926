#pragma once
// The dense-grid LP bound that the open-loop optimality tests compare the SOS program with.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "flatsos/planner/motion_planner.hpp"
#include "flatsos/planner/numerics/linear_program.hpp"

namespace flatsos::test {

/// Lower bound on the SOS program's optimum (quartic flat outputs, one span), independent of the
/// torque and coupling models and of the exchange: Y's quartic coefficients as variables, the
/// boundary equalities as rows, and F(t) = C(q)^-1 [tau; Y] >= reserve (C = [R(q); E] inverted
/// here, at every posture) and Y >= 0 (implied by F >= 0 when E >= 0) only at `points` grid
/// times with the exact torques: a relaxation, so its optimum is <= the program's.
inline double dense_grid_lower_bound(const planner::FlatOutputMap& flat, const planner::OpenLoopPlan& plan,
                                     const planner::MuscleState& s0, const Eigen::VectorXd& reserves, int points) {
  const double T = plan.path.duration_s;
  const int m = flat.numMuscles(), p = flat.numFlatOutputs(), d = 4, nv = p * (d + 1);
  const planner::FlatState y0 = flat.forward(s0);
  std::vector<Eigen::RowVectorXd> rows;
  std::vector<double> lo, hi;
  auto add = [&](const Eigen::RowVectorXd& r, double l, double h) { rows.push_back(r), lo.push_back(l), hi.push_back(h); };
  auto basis = [&](double t, int order) {
    Eigen::RowVectorXd v = Eigen::RowVectorXd::Zero(d + 1);
    for (int k = order; k <= d; ++k) {
      double f = 1;
      for (int i = 0; i < order; ++i) f *= k - i;
      v[k] = f * std::pow(t, k - order);
    }
    return v;
  };
  for (int l = 0; l < p; ++l) {
    for (int order = 0; order < 2; ++order) {
      Eigen::RowVectorXd r = Eigen::RowVectorXd::Zero(nv);
      r.segment(l * (d + 1), d + 1) = basis(0.0, order);
      add(r, y0.Y(l, order), y0.Y(l, order));
    }
    for (int order = 1; order < 3; ++order) {
      Eigen::RowVectorXd r = Eigen::RowVectorXd::Zero(nv);
      r.segment(l * (d + 1), d + 1) = basis(T, order);
      add(r, 0.0, 0.0);
    }
  }
  const int n = flat.numJoints();
  for (int i = 0; i < points; ++i) {
    const double t = T * i / (points - 1);
    const planner::Jet j = plan.path.jet(t, 3);
    const Eigen::VectorXd tau = flat.torque(j.col(0), j.col(1), j.col(2));
    Eigen::MatrixXd C(m, m);
    C << flat.model().momentArmMatrix(j.col(0)), flat.E();
    const Eigen::MatrixXd Cinv = C.inverse();
    for (int k = 0; k < m; ++k) {
      Eigen::RowVectorXd r = Eigen::RowVectorXd::Zero(nv);
      for (int l = 0; l < p; ++l) r.segment(l * (d + 1), d + 1) = Cinv(k, n + l) * basis(t, 0);
      add(r, reserves[k] - Cinv.row(k).head(n).dot(tau), 1e19);
    }
    for (int l = 0; l < p; ++l) {
      Eigen::RowVectorXd r = Eigen::RowVectorXd::Zero(nv);
      r.segment(l * (d + 1), d + 1) = basis(t, 0);
      add(r, 0.0, 1e19);
    }
  }
  planner::LinearProgram lp;
  lp.cost = Eigen::VectorXd::Zero(nv);
  for (int l = 0; l < p; ++l)
    for (int k = 0; k <= d; ++k) lp.cost[l * (d + 1) + k] = std::pow(T, k + 1) / (k + 1);
  lp.G.resize(static_cast<Eigen::Index>(rows.size()), nv);
  for (std::size_t r = 0; r < rows.size(); ++r) lp.G.row(static_cast<Eigen::Index>(r)) = rows[r];
  lp.row_lower = Eigen::Map<Eigen::VectorXd>(lo.data(), static_cast<Eigen::Index>(lo.size()));
  lp.row_upper = Eigen::Map<Eigen::VectorXd>(hi.data(), static_cast<Eigen::Index>(hi.size()));
  lp.x_lower = Eigen::VectorXd::Constant(nv, -1e19);
  lp.x_upper = Eigen::VectorXd::Constant(nv, 1e19);
  const auto r = planner::solve_linear_program(lp);
  EXPECT_EQ(r.status, planner::SolveStatus::Solved) << r.solver_status;
  return r.objective;
}


}  // namespace flatsos::test
