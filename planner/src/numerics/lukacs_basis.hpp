#pragma once
// The polynomial families of the Markov-Lukacs certificates (Bernstein, Chebyshev, monomial),
// each indexed by degree n (n + 1 basis functions), and the linear map from the Gram matrices
// to a polynomial's coefficients in a family.

#include <Eigen/Dense>
#include <string>
#include <utility>
#include <vector>

#include "flatsos/planner/numerics/sos_certificate.hpp"

namespace flatsos::planner::detail {

double binomial(int n, int k);
/// Coefficients (degree n + 1) of s * f, f given by its coefficients c in the degree-n basis.
Eigen::VectorXd times_s(GramBasis b, const Eigen::VectorXd& c);
/// Coefficients (degree n + 1) of (1 - s) * f.
Eigen::VectorXd times_one_minus_s(GramBasis b, const Eigen::VectorXd& c);
/// Coefficients (degree 2d) of phi^d_i * phi^d_j.
Eigen::VectorXd product(GramBasis b, int d, int i, int j);
/// Column k: the monomial coefficients of phi^n_k.
Eigen::MatrixXd to_monomial(GramBasis b, int n);
/// Coefficients in the degree-n family of the polynomial with monomial coefficients c (size n+1).
Eigen::VectorXd from_monomial(GramBasis b, const Eigen::VectorXd& c);

// ---- The linear map from the Gram matrices to p's coefficients. ----

// coefficient_k(p) = <A0[k], Q0> + <A1[k], Q1> (Frobenius products, A symmetric).
struct LukacsOperator {
  int degree = 0;
  int m0 = 0, m1 = 0;
  std::vector<Eigen::MatrixXd> A0, A1;
};

LukacsOperator make_operator(GramBasis b, int n);
/// Family coefficients of v^T Q0 v w0 + v^T Q1 v w1.
Eigen::VectorXd apply_operator(const LukacsOperator& op, const Eigen::MatrixXd& Q0, const Eigen::MatrixXd& Q1);

}  // namespace flatsos::planner::detail
