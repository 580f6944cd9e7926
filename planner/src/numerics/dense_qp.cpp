#include "numerics/dense_qp.hpp"

#include <Eigen/Jacobi>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace flatsos::planner::detail {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// A rotation [c s; -s c] that maps (a, b) to (hypot(a, b), 0); applied to columns i, k of J
// (J G with G = [c -s; s c]) it applies G^T to the rows i, k of J^T n for any n.
struct Givens {
  double c = 1.0, s = 0.0;
};

Givens givens(double a, double b) {
  const double h = std::hypot(a, b);
  return h > 0.0 ? Givens{a / h, b / h} : Givens{};
}

void rotate_columns(Eigen::MatrixXd& J, int i, int k, const Givens& g) {
  // J <- J [c -s; s c] on columns i, k (Eigen's rotation [c s; -s c] with s negated), vectorized.
  J.applyOnTheRight(i, k, Eigen::JacobiRotation<double>(g.c, -g.s));
}

// Appends the row whose J^T a is in w.d to the active set: rotations zero d below position q,
// and R's new column is d's head.
void add_row(DenseQpWorkspace& w, int q, int row) {
  const int n = static_cast<int>(w.J.rows());
  for (int j = n - 1; j > q; --j) {
    const Givens g = givens(w.d[j - 1], w.d[j]);
    w.d[j - 1] = g.c * w.d[j - 1] + g.s * w.d[j];
    w.d[j] = 0.0;
    rotate_columns(w.J, j - 1, j, g);
  }
  w.R.col(q).head(q + 1) = w.d.head(q + 1);
  w.active[static_cast<std::size_t>(q)] = row;
  w.is_active[static_cast<std::size_t>(row)] = 1;
}

// Removes the active row at position l of q: R loses its column and is brought back to upper
// triangular form by rotations of the rows below, which J's columns follow.
void drop_row(DenseQpWorkspace& w, int q, int l) {
  w.is_active[static_cast<std::size_t>(w.active[static_cast<std::size_t>(l)])] = 0;
  for (int k = l; k < q - 1; ++k) {
    w.R.col(k).head(q) = w.R.col(k + 1).head(q);
    w.u[k] = w.u[k + 1];
    w.active[static_cast<std::size_t>(k)] = w.active[static_cast<std::size_t>(k + 1)];
  }
  for (int k = l; k < q - 1; ++k) {
    const Givens g = givens(w.R(k, k), w.R(k + 1, k));
    for (int c = k; c < q - 1; ++c) {
      const double a = w.R(k, c), b = w.R(k + 1, c);
      w.R(k, c) = g.c * a + g.s * b;
      w.R(k + 1, c) = -g.s * a + g.c * b;
    }
    rotate_columns(w.J, k, k + 1, g);
  }
}

[[noreturn]] void refuse_non_finite() { throw std::invalid_argument("dense QP: NaN or Inf in H, g, A or b"); }

// A's rows, dense (column-major) or sparse (row-major): a row's product with x, a row copied out
// dense, every row's norm.
double row_dot(const Eigen::MatrixXd& A, Eigen::Index row, const Eigen::VectorXd& x) { return A.row(row).dot(x); }
double row_dot(const SparseRows& A, Eigen::Index row, const Eigen::VectorXd& x) {
  double sum = 0.0;
  for (SparseRows::InnerIterator it(A, row); it; ++it) sum += it.value() * x[it.index()];
  return sum;
}
void copy_row(const Eigen::MatrixXd& A, Eigen::Index row, Eigen::VectorXd& out) { out = A.row(row).transpose(); }
void copy_row(const SparseRows& A, Eigen::Index row, Eigen::VectorXd& out) {
  out.setZero(A.cols());
  for (SparseRows::InnerIterator it(A, row); it; ++it) out[it.index()] = it.value();
}
void row_norms(const Eigen::MatrixXd& A, Eigen::VectorXd& out) {  // column by column: A is column-major
  out.setZero(A.rows());
  for (Eigen::Index j = 0; j < A.cols(); ++j) out.array() += A.col(j).array().square();
  out = out.cwiseSqrt();
}
void row_norms(const SparseRows& A, Eigen::VectorXd& out) {
  out.resize(A.rows());
  for (Eigen::Index i = 0; i < A.rows(); ++i) out[i] = A.row(i).norm();
}

template <class Rows>
void check_sizes(const Eigen::MatrixXd& H, const Eigen::VectorXd& g, const Rows& A, const Eigen::VectorXd& b) {
  const Eigen::Index n = g.size();
  if (n == 0 || H.rows() != n || H.cols() != n) throw std::invalid_argument("dense QP: H must be n x n with n = size of g > 0");
  if (A.cols() != n || A.rows() != b.size()) throw std::invalid_argument("dense QP: A must be m x n with m = size of b");
  // A's entries are checked through A x in the first pass over its rows (collect_violated):
  // allFinite over A cost as much as that pass.
  if (!H.allFinite() || !g.allFinite() || !b.allFinite()) refuse_non_finite();
}

// Below this slack row i counts as violated.
double violation_threshold(const Eigen::VectorXd& b, Eigen::Index row, double tolerance) {
  return -tolerance * (1.0 + std::abs(b[row]));
}

// A_i x - b_i of one row; x is finite, so a non-finite entry of A_i shows here.
template <class Rows>
double slack_of(const Rows& A, const Eigen::VectorXd& b, const Eigen::VectorXd& x, Eigen::Index row) {
  const double slack = row_dot(A, row, x) - b[row];
  if (!std::isfinite(slack)) refuse_non_finite();
  return slack;
}

template <class Rows>
bool violated_at(const Rows& A, const Eigen::VectorXd& b, const Eigen::VectorXd& x, int row,
                 double tolerance) {
  return slack_of(A, b, x, row) < violation_threshold(b, row, tolerance);
}

// The rows a pass can find violated lie in w.violated as (distance to the row's plane,
// A_i x - b_i over |A_i|, row), most violated taken first from the back.
void list_violated(const Eigen::VectorXd& b, DenseQpWorkspace& w, double tolerance, Eigen::Index row, double slack) {
  if (w.is_active[static_cast<std::size_t>(row)] || slack >= violation_threshold(b, row, tolerance)) return;
  const double norm = w.row_norm[row];
  w.violated.emplace_back(norm > 0.0 ? slack / norm : -kInfinity, static_cast<int>(row));
}

// A x over every row, the row norms once per solve.
template <class Rows>
void full_pass(const Rows& A, const Eigen::VectorXd& b, const Eigen::VectorXd& x, DenseQpWorkspace& w,
               double tolerance) {
  ++w.full_passes;
  w.slack.noalias() = A * x;
  // x is finite: a non-finite entry of A leaves its row's product non-finite.
  if (!w.slack.allFinite()) refuse_non_finite();
  w.slack -= b;
  w.pass_x = x;
  if (w.row_norm.size() != A.rows()) row_norms(A, w.row_norm);
  for (Eigen::Index i = 0; i < A.rows(); ++i) list_violated(b, w, tolerance, i, w.slack[i]);
}

// After a full pass, a row whose slack then exceeded |A_i| |x - x_then| still holds
// (Cauchy-Schwarz); the others are computed alone. False, with nothing listed, when they are more
// than kMostRowsComputedAlone of the rows (a full pass is cheaper then) or there was no full pass.
constexpr double kMostRowsComputedAlone = 0.125;
template <class Rows>
bool partial_pass(const Rows& A, const Eigen::VectorXd& b, const Eigen::VectorXd& x, DenseQpWorkspace& w,
                  double tolerance) {
  if (w.pass_x.size() != x.size()) return false;
  const double moved = (x - w.pass_x).norm();
  w.candidates.clear();
  for (Eigen::Index i = 0; i < A.rows(); ++i)
    if (!w.is_active[static_cast<std::size_t>(i)] &&
        w.slack[i] - w.row_norm[i] * moved < violation_threshold(b, i, tolerance))
      w.candidates.push_back(static_cast<int>(i));
  if (static_cast<double>(w.candidates.size()) > kMostRowsComputedAlone * static_cast<double>(A.rows())) return false;
  ++w.partial_passes;
  for (const int i : w.candidates) list_violated(b, w, tolerance, i, slack_of(A, b, x, i));
  return true;
}

// Every row violated at x into w.violated, most violated last; false when every row holds to
// the tolerance. One pass serves the additions until its list is used up (each rechecked at the x
// of its turn): a pass per addition (A x over some 13 000 rows) was most of a QP's time.
template <class Rows>
bool collect_violated(const Rows& A, const Eigen::VectorXd& b, const Eigen::VectorXd& x, DenseQpWorkspace& w,
                      double tolerance) {
  w.violated.clear();
  if (!partial_pass(A, b, x, w, tolerance)) full_pass(A, b, x, w, tolerance);
  std::sort(w.violated.begin(), w.violated.end());
  std::reverse(w.violated.begin(), w.violated.end());  // taken from the back: most violated first
  return !w.violated.empty();
}

// The next row to add: a hinted one, else one of the last pass's (in its order) still violated
// at x, else the most violated of a new pass; -1 when every row holds.
template <class Rows>
int next_violated(const Rows& A, const Eigen::VectorXd& b, const Eigen::VectorXd& x, DenseQpWorkspace& w,
                  double tolerance) {
  while (true) {
    while (!w.violated.empty()) {
      const int row = w.violated.back().second;
      w.violated.pop_back();
      if (!w.is_active[static_cast<std::size_t>(row)] && violated_at(A, b, x, row, tolerance)) return row;
    }
    if (!collect_violated(A, b, x, w, tolerance)) return -1;
  }
}

// The hinted rows as the start's active set, all at once: with J0 = L^-T and L^-1 A_S^T = Q [R; 0]
// (a Householder QR), J = J0 Q, x the minimum on A_S x = b_S and u its multipliers,
//   x = -J2 J2^T g + J1 R^-T b_S,  u = R^-1 (J1^T g + R^-T b_S),
// the state the row-by-row additions reach when every multiplier stays >= 0 (Goldfarb and Idnani
// 1983, section 3), for one factorization instead of a rotation sweep and two products with J per
// row. Of the hint's first n valid rows, those with a negative multiplier leave and the rest are
// factored again (kWarmStartRounds at most). False, with w as the cold start left it, when no such
// set remains or the rows are dependent; the caller then adds the hinted rows one by one.
constexpr int kWarmStartRounds = 3;
constexpr double kDependentRow = 1e-10;  // |R_kk| below this times the largest: dependent rows

template <class Rows>
bool start_on_hinted_rows(const Eigen::LLT<Eigen::MatrixXd>& cholesky, const Eigen::VectorXd& g, const Rows& A,
                          const Eigen::VectorXd& b, const std::vector<int>& hint, DenseQpWorkspace& w, Eigen::VectorXd& x,
                          int& q) {
  const Eigen::Index n = g.size(), m = A.rows();
  std::vector<int> rows;
  std::vector<char> taken(static_cast<std::size_t>(m), 0);
  for (const int row : hint)  // the first n valid ones: more cannot be independent
    if (row >= 0 && row < m && !taken[static_cast<std::size_t>(row)] && static_cast<Eigen::Index>(rows.size()) < n)
      taken[static_cast<std::size_t>(row)] = 1, rows.push_back(row);
  for (int round = 0; round < kWarmStartRounds && !rows.empty(); ++round) {
    const auto k = static_cast<Eigen::Index>(rows.size());
    Eigen::MatrixXd M(n, k);
    for (Eigen::Index c = 0; c < k; ++c) {
      copy_row(A, rows[static_cast<std::size_t>(c)], w.row);
      M.col(c) = w.row;
    }
    cholesky.matrixL().solveInPlace(M);  // L^-1 A_S^T
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(M);
    Eigen::MatrixXd R = qr.matrixQR().topRows(k).triangularView<Eigen::Upper>();
    Eigen::MatrixXd Q = qr.householderQ();
    const double largest = R.diagonal().cwiseAbs().maxCoeff();
    if (!(largest > 0.0) || R.diagonal().cwiseAbs().minCoeff() <= kDependentRow * largest) return false;
    for (Eigen::Index c = 0; c < k; ++c)  // R's diagonal positive, as the rotations leave it
      if (R(c, c) < 0.0) R.row(c) *= -1.0, Q.col(c) *= -1.0;
    Eigen::VectorXd b_S(k);
    for (Eigen::Index c = 0; c < k; ++c) b_S[c] = b[rows[static_cast<std::size_t>(c)]];
    cholesky.matrixL().transpose().solveInPlace(Q);  // J = L^-T Q
    const Eigen::VectorXd y = R.transpose().triangularView<Eigen::Lower>().solve(b_S);  // R^-T b_S
    const Eigen::VectorXd u = R.triangularView<Eigen::Upper>().solve(Q.leftCols(k).transpose() * g + y);
    if (!u.allFinite()) return false;
    if (u.minCoeff() < 0.0) {
      std::vector<int> kept;
      for (Eigen::Index c = 0; c < k; ++c)
        if (u[c] >= 0.0) kept.push_back(rows[static_cast<std::size_t>(c)]);
      rows.swap(kept);
      continue;
    }
    w.J = std::move(Q);
    x = -w.J.rightCols(n - k) * (w.J.rightCols(n - k).transpose() * g) + w.J.leftCols(k) * y;
    w.R.topLeftCorner(k, k) = R;
    w.u.head(k) = u;
    for (Eigen::Index c = 0; c < k; ++c) {
      w.active[static_cast<std::size_t>(c)] = rows[static_cast<std::size_t>(c)];
      w.is_active[static_cast<std::size_t>(rows[static_cast<std::size_t>(c)])] = 1;
    }
    q = static_cast<int>(k);
    return true;
  }
  return false;
}

template <class Rows>
DenseQpResult solve(const Eigen::MatrixXd& H, const Eigen::VectorXd& g, const Rows& A, const Eigen::VectorXd& b,
                    DenseQpWorkspace& w, Eigen::VectorXd& x, Eigen::VectorXd* multipliers, double feasibility_tolerance,
                    const std::vector<int>* hint) {
  check_sizes(H, g, A, b);
  const int n = static_cast<int>(g.size()), m = static_cast<int>(A.rows());
  w.cholesky.compute(H);
  if (w.cholesky.info() != Eigen::Success) throw std::invalid_argument("dense QP: H is not positive definite");
  DenseQpResult result;
  x = w.cholesky.solve(-g);
  // J = L^-T: J^T H J = I.
  w.J.setIdentity(n, n);
  w.cholesky.matrixL().transpose().solveInPlace(w.J);
  const double j_squared_norm = w.J.squaredNorm();  // the rotations below keep it
  w.R.setZero(n, n);
  w.d.resize(n);
  w.z.resize(n);
  w.r.resize(n);
  w.u.setZero(n + 1);
  w.active.assign(static_cast<std::size_t>(n), -1);
  w.is_active.assign(static_cast<std::size_t>(m), 0);
  w.violated.clear();
  w.pass_x.resize(0);  // no pass over this A yet
  w.full_passes = w.partial_passes = 0;
  w.row_norm.resize(0);
  int q = 0;
  const int max_iterations = 10 * (n + m) + 10;
  std::size_t next_hint = 0;
  // A sequential QP's next QP mostly keeps the last one's active rows: factored at once, the
  // additions then only find what changed.
  w.started_rows = 0;
  if (hint && start_on_hinted_rows(w.cholesky, g, A, b, *hint, w, x, q)) next_hint = hint->size(), w.started_rows = q;
  while (true) {
    // The hinted rows first, each while violated (any violated row may join: the order only
    // changes the work), then the most violated of all.
    int p = -1;
    while (hint && next_hint < hint->size() && p < 0) {
      const int row = (*hint)[next_hint++];
      if (row >= 0 && row < m && !w.is_active[static_cast<std::size_t>(row)] &&
          violated_at(A, b, x, row, feasibility_tolerance))
        p = row;
    }
    if (p < 0) p = next_violated(A, b, x, w, feasibility_tolerance);
    if (p < 0) break;
    copy_row(A, p, w.row);  // contiguous: a dense A is column-major, its rows strided by m
    double u_new = 0.0;  // the multiplier of row p while it joins
    while (true) {
      if (++result.iterations > max_iterations) {
        result.failure = "no convergence in " + std::to_string(max_iterations) + " active-set changes";
        return result;
      }
      w.d.noalias() = w.J.transpose() * w.row;
      w.z.noalias() = w.J.rightCols(n - q) * w.d.tail(n - q);
      if (q > 0) w.r.head(q) = w.R.topLeftCorner(q, q).triangularView<Eigen::Upper>().solve(w.d.head(q));
      // Partial step: the first active multiplier to reach zero.
      double t_partial = kInfinity;
      int l = -1;
      for (int k = 0; k < q; ++k)
        if (w.r[k] > 0.0 && w.u[k] / w.r[k] < t_partial) t_partial = w.u[k] / w.r[k], l = k;
      // Full step: onto row p's plane (z^T a_p = |J2^T a_p|^2 >= 0).
      const double za = w.z.dot(w.row);
      const double scale = w.row.squaredNorm();
      const double s_p = w.row.dot(x) - b[p];
      const double t_full = za > 1e-14 * scale * j_squared_norm / n ? -s_p / za : kInfinity;
      const double t = std::min(t_partial, t_full);
      if (t == kInfinity) {
        result.failure = "infeasible: row " + std::to_string(p) + " cannot be met with the active rows";
        return result;
      }
      if (q > 0) w.u.head(q) -= t * w.r.head(q);
      u_new += t;
      if (t_full < kInfinity) x += t * w.z;
      if (t_full <= t_partial) {
        add_row(w, q, p);
        w.u[q] = u_new;
        ++q;
        break;
      }
      drop_row(w, q, l);
      --q;
    }
  }
  result.solved = true;
  w.active.resize(static_cast<std::size_t>(q));
  result.objective = 0.5 * x.dot(H * x) + g.dot(x);
  if (multipliers) {
    multipliers->setZero(m);
    for (int k = 0; k < q; ++k) (*multipliers)[w.active[static_cast<std::size_t>(k)]] = std::max(w.u[k], 0.0);
  }
  return result;
}

}  // namespace

DenseQpResult solve_dense_qp(const Eigen::MatrixXd& H, const Eigen::VectorXd& g, const Eigen::MatrixXd& A,
                             const Eigen::VectorXd& b, DenseQpWorkspace& w, Eigen::VectorXd& x,
                             Eigen::VectorXd* multipliers, double feasibility_tolerance, const std::vector<int>* hint) {
  return solve(H, g, A, b, w, x, multipliers, feasibility_tolerance, hint);
}

DenseQpResult solve_dense_qp(const Eigen::MatrixXd& H, const Eigen::VectorXd& g, const SparseRows& A,
                             const Eigen::VectorXd& b, DenseQpWorkspace& w, Eigen::VectorXd& x,
                             Eigen::VectorXd* multipliers, double feasibility_tolerance, const std::vector<int>* hint) {
  return solve(H, g, A, b, w, x, multipliers, feasibility_tolerance, hint);
}

}  // namespace flatsos::planner::detail
