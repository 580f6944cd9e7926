#pragma once
// A problem of the bounds' shape, independent of muscles, for the sequential LP and the methods
// beside it: a linear cost over many smooth concave rows ">= 0" and linear reserve rows.

#include <algorithm>
#include <random>

#include <Eigen/Core>

#include "bounds/sequential_lp.hpp"

namespace flatsos::testing {

namespace fpd = flatsos::planner::detail;

// r_i(x) = a_i . x - b_i - kappa_i / 2 |x - c|^2: concave, so the feasible set is convex and the
// optimum of a positive cost over x >= 0 is unique.
struct ConcaveRows {
  Eigen::MatrixXd a;
  Eigen::VectorXd b, kappa, c;

  ConcaveRows(int rows, int n, unsigned seed) : a(rows, n), b(rows), kappa(rows), c(Eigen::VectorXd::Constant(n, 3.0)) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int i = 0; i < rows; ++i) {
      for (int j = 0; j < n; ++j) a(i, j) = 0.1 + unit(rng);
      b[i] = 0.5 + unit(rng);
      kappa[i] = 0.01 + 0.05 * unit(rng);
    }
  }

  fpd::BoundRowsAt operator()(const Eigen::VectorXd& x, bool jacobian) const {
    fpd::BoundRowsAt out;
    for (Eigen::Index i = 0; i < a.rows(); ++i) {
      const double v = a.row(i).dot(x) - b[i] - 0.5 * kappa[i] * (x - c).squaredNorm();
      out.value.push_back(v);
      out.violation += std::max(0.0, -v);
      if (jacobian)
        for (Eigen::Index j = 0; j < x.size(); ++j)
          out.jacobian.emplace_back(static_cast<int>(i), static_cast<int>(j), a(i, j) - kappa[i] * (x[j] - c[j]));
    }
    return out;
  }
};

struct Problem {
  static constexpr int kVariables = 6, kRows = 400, kReserveRows = 60;
  ConcaveRows rows{kRows, kVariables, 5};
  flatsos::planner::LinearProgram lp;

  Problem() {
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    lp.cost = Eigen::VectorXd::LinSpaced(kVariables, 1.0, 2.0);
    lp.G.resize(kReserveRows, kVariables);
    lp.row_lower.resize(kReserveRows);
    for (int r = 0; r < kReserveRows; ++r) {
      for (int j = 0; j < kVariables; ++j) lp.G(r, j) = unit(rng);
      lp.row_lower[r] = 2.0 * unit(rng);
    }
    lp.row_upper = Eigen::VectorXd::Constant(kReserveRows, 1e19);
    lp.x_lower = Eigen::VectorXd::Zero(kVariables);
    lp.x_upper = Eigen::VectorXd::Constant(kVariables, 1e19);
  }

  struct Solved {
    fpd::SequentialLpOutcome outcome;
    Eigen::VectorXd x;
  };
  Solved solve(bool working_set, int closest_rows_per_coefficient = 8) const {
    const fpd::SequentialLpLinearPart linear{lp, {static_cast<std::size_t>(kReserveRows)}, 1e-6};
    Solved s{{}, Eigen::VectorXd::Zero(kVariables)};
    double radius = 0.1;
    flatsos::planner::SequentialLpBasis basis;
    fpd::SequentialLpSettings settings;
    settings.working_set = working_set;
    settings.closest_rows_per_coefficient = closest_rows_per_coefficient;
    s.outcome = fpd::solve_by_sequential_lp(linear, rows, s.x, radius, basis, settings);
    return s;
  }
};


}  // namespace flatsos::testing
