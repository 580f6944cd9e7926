#pragma once
// A small dense strictly convex quadratic program,
//   minimize 0.5 x^T H x + g^T x  subject to  A x >= b,
// by the dual active-set method of Goldfarb and Idnani (1983, "A numerically stable dual method
// for solving strictly convex quadratic programs", Math. Programming 27:1-33): it starts at the
// unconstrained minimum and adds the most violated row at a time, dropping rows whose multiplier
// would turn negative, with the factors J = L^-T Q and R (A_active^T L^-T = Q [R; 0]) updated by
// Givens rotations. Each step of the effort's sequential QP (a handful of coefficients, a few
// hundred rows) solves one in tens of microseconds, where Clp's quadratic simplex took 1.5 ms.
// Debian packages no small dense QP solver.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/SparseCore>

namespace flatsos::planner::detail {

/// A's rows stored sparse, row by row: the effort's bound and reserve rows touch a few dozen of a
/// plan's hundreds of coefficients each.
using SparseRows = Eigen::SparseMatrix<double, Eigen::RowMajor>;

/// Buffers reused between solves of the same size (no allocation once sized).
struct DenseQpWorkspace {
  Eigen::LLT<Eigen::MatrixXd> cholesky;
  Eigen::MatrixXd J, R;
  Eigen::VectorXd d, z, r, u, slack, row;  // row: the joining row of A, contiguous
  std::vector<int> active;      // row indices of the active set, in R's column order (after a solve: those at its optimum)
  std::vector<char> is_active;  // per row
  std::vector<std::pair<double, int>> violated;  // the last pass's violated rows (distance, row), most first
  Eigen::VectorXd row_norm, pass_x;  // |A_i|; x at the last full pass (slack holds A x - b there)
  std::vector<int> candidates;       // rows a partial pass computes
  int full_passes = 0, partial_passes = 0;  // over the rows, in the last solve
  int started_rows = 0;  // hinted rows the last solve started with, factored at once (0: one by one)
};

struct DenseQpResult {
  bool solved = false;
  std::string failure;      // why not, when not solved
  int iterations = 0;       // rows added or dropped
  double objective = 0.0;   // 0.5 x^T H x + g^T x at x
};

/// Solves into x; `multipliers` (one per row, >= 0, 0 off the active set) when not null.
/// H must be symmetric positive definite (throws std::invalid_argument otherwise, or on sizes).
/// `feasibility_tolerance`: a row counts as met when A_i x - b_i >= -tolerance (1 + |b_i|).
/// `hint`: rows to start from: a sequence of similar QPs passes the last one's active rows
/// (workspace.active after a solve). Those whose multipliers are >= 0 on them are factored at once
/// as the start's active set; where none such are independent, they are tried one by one, each
/// joining while violated. Either spares most scans of every row for the most violated (the same
/// optimum; on the open-loop effort's 3000 rows and 200 coefficients most of the time).
DenseQpResult solve_dense_qp(const Eigen::MatrixXd& H, const Eigen::VectorXd& g, const Eigen::MatrixXd& A,
                             const Eigen::VectorXd& b, DenseQpWorkspace& workspace, Eigen::VectorXd& x,
                             Eigen::VectorXd* multipliers = nullptr, double feasibility_tolerance = 1e-10,
                             const std::vector<int>* hint = nullptr);
/// The same with A's rows sparse: every pass over the rows costs their nonzeros, not m n.
DenseQpResult solve_dense_qp(const Eigen::MatrixXd& H, const Eigen::VectorXd& g, const SparseRows& A,
                             const Eigen::VectorXd& b, DenseQpWorkspace& workspace, Eigen::VectorXd& x,
                             Eigen::VectorXd* multipliers = nullptr, double feasibility_tolerance = 1e-10,
                             const std::vector<int>* hint = nullptr);

}  // namespace flatsos::planner::detail
