#pragma once
// Exact algebra on Lukacs certificates: triangular factors, multiplying a certificate by s,
// 1 - s or (s - r)^2, adding certificates, splitting a polynomial at its near-zero minima
// (deflation) and undoing the splits, the closed-form diagonal Bernstein certificate, residuals.

#include <Eigen/Dense>
#include <string>
#include <utility>
#include <vector>

#include "flatsos/planner/numerics/sos_certificate.hpp"
#include "numerics/lukacs_basis.hpp"

namespace flatsos::planner::detail {

// One deflation step: current = w * next + rest with w = s, 1 - s or (s - r)^2. rest (degree
// < degree of w) is either negligible (empty here: dropped, it shows in the residual) or >= 0 on
// [0, 1] (a constant, or a linear function with both end values >= 0), certified on its own.
struct DeflationStep {
  enum Kind { AtZero, AtOne, Square } kind = Square;
  double r = 0.0;
  Eigen::VectorXd rest;
};

/// Lower-triangular factor with the same L L^T (L is r x c, any c; the result r x r).
Eigen::MatrixXd lower_triangular_factor(const Eigen::MatrixXd& L);
/// Row i: the coefficients in the degree-(d+1) family of w * phi^d_i, w = s (by_s) or 1 - s.
Eigen::MatrixXd multiplication_matrix(GramBasis b, int d, bool by_s);
/// The certificate of w q (w = s or 1 - s) from that of q.
void multiply_certificate(LukacsCertificate& c, bool by_s);
/// Multiplies the certificate by (s - r)^2.
void multiply_certificate_by_square(LukacsCertificate& c, double r);
/// Gram matrices add: [La Lb] [La Lb]^T = La La^T + Lb Lb^T.
void add_certificate(LukacsCertificate& c, const LukacsCertificate& other);
/// Synthetic division by (s - r): q = (s - r) h + q(r).
std::pair<Eigen::VectorXd, double> divide_by_linear(const Eigen::VectorXd& q, double r);

struct Deflation {
  Eigen::VectorXd q;  // what is left to certify
  std::vector<DeflationStep> steps;
};

/// Splits off the factor at the global minimum of p on [0, 1] while that minimum is below
/// relative_threshold * max|Bernstein coefficient|; values below drop_threshold are dropped.
Deflation deflate(const Eigen::VectorXd& p, double relative_threshold, double drop_threshold);
/// The certificate of p from that of the deflated q: the steps undone, last first.
LukacsCertificate undo_deflation(LukacsCertificate c, const std::vector<DeflationStep>& steps);
/// Diagonal Gram in the Bernstein basis from Bernstein coefficients beta (factors sqrt(diag)).
std::pair<Eigen::VectorXd, Eigen::VectorXd> bernstein_diagonal(const LukacsOperator& bern, const Eigen::VectorXd& beta);
/// The closed-form certificate of q (monomial coefficients): diagonal Bernstein Gram of its
/// clipped Bernstein coefficients (exact if they are >= 0).
LukacsCertificate bernstein_diagonal_certificate(const Eigen::VectorXd& q);
/// Factor in basis b of the Gram diag(l.^2) given in the Bernstein basis of the same degree.
Eigen::MatrixXd convert_diagonal_factor(GramBasis b, const Eigen::VectorXd& l);
/// Residuals of the certificate against p (monomial coefficients).
void fill_residual(LukacsCertificate& cert, const Eigen::VectorXd& p_monomial);

}  // namespace flatsos::planner::detail
