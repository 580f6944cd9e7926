#pragma once
// The batch L L^T program: one Ipopt problem for the Gram factors of many polynomials at once
// (variables: the factors' entries; equality constraints: the coefficient matching, quadratic in
// the factors; zero objective or a proximal term; exact Jacobian and Hessian).

#include <Eigen/Dense>
#include <string>
#include <utility>
#include <vector>

#include "flatsos/planner/numerics/sos_certificate.hpp"
#include "numerics/lukacs_algebra.hpp"
#include "numerics/lukacs_basis.hpp"
#include "flatsos/planner/numerics/sos_certificate_study.hpp"

namespace flatsos::planner::detail {

// How the entries of one m x m factor are laid out among Ipopt's variables, column by column:
// a full square factor (rows 0..m-1 of every column) or a lower-triangular one (rows c..m-1).
struct FactorLayout {
  bool full = true;
  int first_row(int c) const { return full ? 0 : c; }
  int size(int m) const { return full ? m * m : m * (m + 1) / 2; }
  int index(int m, int i, int c) const {
    return full ? c * m + i : c * m - c * (c - 1) / 2 + (i - c);
  }
  void pack(const Eigen::MatrixXd& L, std::vector<double>& out) const {
    for (int c = 0; c < static_cast<int>(L.cols()); ++c)
      for (int i = first_row(c); i < static_cast<int>(L.rows()); ++i) out.push_back(L(i, c));
  }
};

struct Block {
  std::size_t poly = 0;                  // index into the input
  std::vector<DeflationStep> deflation;  // the block certifies q; p = q with these steps undone
  LukacsOperator op;
  Eigen::VectorXd target;  // normalized family coefficients of q (the deflated p, maybe shifted)
  double normalization = 1.0;  // q_family = normalization * target
  // Constraint weight: Ipopt sees weight * (A(L L^T) - target), so that a violation of tau in
  // every constraint means a relative residual of at most tau in q's monomial coefficients.
  double weight = 1.0;
  int var_offset = 0;           // first variable (L0 entries, then L1 entries)
  int con_offset = 0;           // first constraint (coefficients 0..degree)
  Eigen::MatrixXd start_L0, start_L1;  // start factors (normalized)
  std::vector<double> start;    // the same as Ipopt variables (set by LukacsNlp)
};

struct IpoptRun {
  std::string status;
  std::string linear_solver;
  int iterations = 0;
  int variables = 0;
  int constraints = 0;
  std::vector<std::pair<Eigen::MatrixXd, Eigen::MatrixXd>> factors;  // per block (normalized); empty: no point
  std::string derivative_report;
  int derivative_errors = -1;
};

/// One Ipopt call on all the blocks.
IpoptRun run_ipopt(std::vector<Block>& blocks, FactorLayout layout, const CertificationStudyOptions& options, double tol,
                   bool derivative_test);

}  // namespace flatsos::planner::detail
