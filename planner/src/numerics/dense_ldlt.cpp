#include "numerics/dense_ldlt.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <Eigen/Core>

namespace flatsos::planner::detail {
namespace {

using Matrix = Eigen::Map<Eigen::MatrixXd>;
using ConstMatrix = Eigen::Map<const Eigen::MatrixXd>;

// Bunch and Kaufman's constant: it bounds the growth of the entries per step by (1 + 1/alpha)
// for a 1x1 pivot and (1 + 1/alpha)^2 for a 2x2 pivot, with equal bounds per eliminated row.
const double kAlpha = (1.0 + std::sqrt(17.0)) / 8.0;

// Interchanges rows and columns p < q of the symmetric matrix whose lower triangle `a` holds,
// together with rows p and q of the L columns already computed (columns before p).
void swap_symmetric(Matrix& a, int p, int q) {
  const int n = static_cast<int>(a.rows());
  for (int j = 0; j < p; ++j) std::swap(a(p, j), a(q, j));
  std::swap(a(p, p), a(q, q));
  for (int j = p + 1; j < q; ++j) std::swap(a(j, p), a(q, j));
  for (int i = q + 1; i < n; ++i) std::swap(a(i, p), a(i, q));
}

// Largest |entry| of row and column r of the trailing matrix [k, n), diagonal excluded.
double off_diagonal_max(const Matrix& a, int k, int r) {
  const int n = static_cast<int>(a.rows());
  double m = 0.0;
  if (r > k) m = a.row(r).segment(k, r - k).cwiseAbs().maxCoeff();
  if (r + 1 < n) m = std::max(m, a.col(r).tail(n - r - 1).cwiseAbs().maxCoeff());
  return m;
}

void count(Inertia& inertia, double eigenvalue) {
  if (eigenvalue > 0.0) ++inertia.positive;
  else if (eigenvalue < 0.0) ++inertia.negative;
  else ++inertia.zero;
}

}  // namespace

Inertia factor_ldlt_in_place(double* data, int n, int* pivots, double zero_pivot) {
  Matrix a(data, n, n);
  Inertia inertia;
  int k = 0;
  while (k < n) {
    const int below = n - k - 1;
    const double abs_akk = std::abs(a(k, k));
    int r = k;
    double col_max = 0.0;
    if (below > 0) {
      Eigen::Index i = 0;
      col_max = a.col(k).tail(below).cwiseAbs().maxCoeff(&i);
      r = k + 1 + static_cast<int>(i);
    }
    if (!(std::max(abs_akk, col_max) > zero_pivot)) {  // also NaN: never divide by it
      a.col(k).tail(n - k).setZero();
      pivots[k] = k;
      ++inertia.zero;
      ++k;
      continue;
    }
    // Choose the pivot: 1x1 at k, 1x1 at r, or the 2x2 block (k, r).
    int step = 1, partner = k;
    if (abs_akk < kAlpha * col_max) {
      const double row_max = off_diagonal_max(a, k, r);
      if (abs_akk * row_max >= kAlpha * col_max * col_max) {
        partner = k;
      } else if (std::abs(a(r, r)) >= kAlpha * row_max) {
        partner = r;
      } else {
        partner = r;
        step = 2;
      }
    }
    const int moved = k + step - 1;  // the row that trades places with `partner`
    if (partner != moved) swap_symmetric(a, moved, partner);

    if (step == 1) {
      const double d = a(k, k);
      if (below > 0) {
        a.block(k + 1, k + 1, below, below).selfadjointView<Eigen::Lower>().rankUpdate(a.col(k).tail(below), -1.0 / d);
        a.col(k).tail(below) /= d;
      }
      pivots[k] = partner;
      count(inertia, d);
    } else {
      const double d11 = a(k, k), d21 = a(k + 1, k), d22 = a(k + 1, k + 1);
      const double det = d11 * d22 - d21 * d21;  // < 0 by the pivot rule
      const int rest = n - k - 2;
      if (rest > 0) {
        auto c1 = a.col(k).tail(rest);
        auto c2 = a.col(k + 1).tail(rest);
        // Trailing -= C D^-1 C^T with C = [c1 c2] and D^-1 = [d22 -d21; -d21 d11] / det.
        auto trailing = a.block(k + 2, k + 2, rest, rest).selfadjointView<Eigen::Lower>();
        trailing.rankUpdate(c1, -d22 / det);
        trailing.rankUpdate(c2, -d11 / det);
        trailing.rankUpdate(c1, c2, d21 / det);
        for (int i = 0; i < rest; ++i) {  // [l1 l2] = C D^-1, row by row (no temporary)
          const double x1 = c1(i), x2 = c2(i);
          c1(i) = (d22 * x1 - d21 * x2) / det;
          c2(i) = (d11 * x2 - d21 * x1) / det;
        }
      }
      pivots[k] = pivots[k + 1] = -partner - 1;
      // The block's eigenvalues: opposite signs when det < 0, the trace's sign when det > 0.
      if (det < 0.0) {
        ++inertia.positive;
        ++inertia.negative;
      } else {
        const double trace = d11 + d22;
        count(inertia, trace);
        count(inertia, det > 0.0 ? trace : 0.0);
      }
    }
    k += step;
  }
  return inertia;
}

void solve_ldlt_in_place(const double* data, int n, const int* pivots, double* rhs) {
  ConstMatrix a(data, n, n);
  Eigen::Map<Eigen::VectorXd> b(rhs, n);
  // b <- P b: the interchanges in the order they were made.
  for (int k = 0; k < n;) {
    const bool block = pivots[k] < 0;
    const int partner = block ? -pivots[k] - 1 : pivots[k];
    const int moved = block ? k + 1 : k;
    if (partner != moved) std::swap(b(moved), b(partner));
    k += block ? 2 : 1;
  }
  // b <- L^-1 b, then D^-1 b.
  for (int k = 0; k < n;) {
    if (pivots[k] >= 0) {
      if (k + 1 < n) b.tail(n - k - 1) -= b(k) * a.col(k).tail(n - k - 1);
      k += 1;
    } else {
      if (k + 2 < n) b.tail(n - k - 2) -= b(k) * a.col(k).tail(n - k - 2) + b(k + 1) * a.col(k + 1).tail(n - k - 2);
      k += 2;
    }
  }
  for (int k = 0; k < n;) {
    if (pivots[k] >= 0) {
      b(k) = a(k, k) != 0.0 ? b(k) / a(k, k) : 0.0;  // a zero pivot's component is set to 0
      k += 1;
    } else {
      const double d11 = a(k, k), d21 = a(k + 1, k), d22 = a(k + 1, k + 1);
      const double det = d11 * d22 - d21 * d21;
      const double b1 = b(k), b2 = b(k + 1);
      b(k) = (d22 * b1 - d21 * b2) / det;
      b(k + 1) = (d11 * b2 - d21 * b1) / det;
      k += 2;
    }
  }
  // b <- L^-T b, blocks from the last.
  for (int k = n - 1; k >= 0;) {
    if (k > 0 && pivots[k] < 0) {  // the second row of a 2x2 block at k - 1
      const int j = k - 1, rest = n - k - 1;
      if (rest > 0) {
        b(j) -= a.col(j).tail(rest).dot(b.tail(rest));
        b(k) -= a.col(k).tail(rest).dot(b.tail(rest));
      }
      k -= 2;
    } else {
      if (k + 1 < n) b(k) -= a.col(k).tail(n - k - 1).dot(b.tail(n - k - 1));
      k -= 1;
    }
  }
  // b <- P^T b: the interchanges undone in reverse order.
  for (int k = n - 1; k >= 0;) {
    const bool block = pivots[k] < 0;
    const int first = block ? k - 1 : k;
    const int partner = block ? -pivots[k] - 1 : pivots[k];
    const int moved = block ? first + 1 : first;
    if (partner != moved) std::swap(b(moved), b(partner));
    k = first - 1;
  }
}

DenseLdlt::DenseLdlt(const Eigen::MatrixXd& a, double zero_pivot)
    : n_(static_cast<int>(a.rows())), factor_(a), pivots_(static_cast<std::size_t>(a.rows())) {
  if (a.rows() != a.cols()) throw std::invalid_argument("dense LDL^T: the matrix is not square");
  inertia_ = factor_ldlt_in_place(factor_.data(), n_, pivots_.data(), zero_pivot);
}

Eigen::VectorXd DenseLdlt::solve(const Eigen::VectorXd& b) const {
  if (b.size() != n_) throw std::invalid_argument("dense LDL^T: the right-hand side has the wrong size");
  Eigen::VectorXd x = b;
  solve_ldlt_in_place(factor_.data(), n_, pivots_.data(), x.data());
  return x;
}

}  // namespace flatsos::planner::detail
