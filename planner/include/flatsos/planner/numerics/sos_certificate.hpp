#pragma once
// Markov-Lukacs sum-of-squares certificates of nonnegativity on [0, 1] (docs/method/sos_certificates.md).
//
// A polynomial p of degree n is >= 0 on [0, 1] iff
//   n = 2d:     p(s) = v_d(s)^T Q0 v_d(s) + s (1 - s) v_{d-1}(s)^T Q1 v_{d-1}(s),  Q0 (d+1), Q1 (d)
//   n = 2d + 1: p(s) = s v_d(s)^T Q0 v_d(s) + (1 - s) v_d(s)^T Q1 v_d(s),         Q0, Q1 (d+1)
// with Q0, Q1 positive semidefinite. The Gram matrices are found as Q = L L^T by ONE Ipopt
// problem for a whole batch of polynomials (block diagonal; Ipopt costs about 5 ms per call
// whatever the size): variables = the entries of every factor L (full square factors: measured
// far more robust than triangular ones at singular solutions; the returned factors are made lower
// triangular by a QR), equality constraints = the coefficient matching (quadratic in L), zero
// objective, exact Jacobian and exact Hessian of the Lagrangian. Blocks that fail get one second
// call with triangular factors.
//
// v_d(s) is a polynomial basis of degree d; the default is the Bernstein basis
// B^d_k(s) = C(d,k) s^k (1-s)^(d-k), matched in the Bernstein basis of degree n. With it each
// diagonal entry of Q0 / Q1 feeds exactly one Bernstein coefficient of p, so a diagonal Gram is an
// exact certificate whenever p's Bernstein coefficients are >= 0 (the closed-form shortcut, no
// Ipopt), and otherwise the diagonal Gram built from the clipped Bernstein coefficients is the
// Ipopt start.
//
// Polynomials that come near zero on [0, 1] (the ones that matter: active constraints) make the
// L L^T program nearly singular. They are first split at their global minimum, exactly:
// p = s q + p(0), (1-s) q + p(1) or (s-r)^2 q + (linear >= 0), repeatedly; q (well conditioned)
// goes to Ipopt or the closed form, and the certificate of p is assembled from q's. The
// measurements behind these choices: docs/method/sos_certificates.md; the knobs they compared:
// sos_certificate_study.hpp.
//
// What "certified" proves. The certificate's factors rebuild a polynomial r that is >= 0 on [0, 1]
// by construction (up to rounding in forming L L^T). The residual e = p - r is reported, with a
// bound residual_bound >= max |e| on [0, 1], so p >= -residual_bound there. A polynomial is
// certified when max_k |e_k| <= tolerance * scale (scale = max_k |p_k|, monomial coefficients) AND
// the numeric pre-check (minimum_on_interval) finds no value below -tolerance * scale. So
// "certified" means "nonnegative on [0, 1] up to (degree + 1) * tolerance * scale"; exact zeros
// (double roots, endpoint zeros) are certified in this sense. A polynomial whose computed minimum m
// is slightly negative (-tolerance * scale <= m < 0) is certified through p + delta, delta = -m +
// 0.01 * tolerance * scale, which shows in its residual.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "flatsos/planner/numerics/polynomial.hpp"

namespace flatsos::planner {

/// Basis of v_d(s) (and of the coefficient matching: the same family at degree n).
enum class GramBasis {
  Bernstein,  ///< B^d_k(s) = C(d,k) s^k (1-s)^(d-k) (default, measured best)
  Chebyshev,  ///< T_k(2s - 1)
  Monomial,   ///< s^k
};
std::string gram_basis_name(GramBasis basis);

struct LukacsCertificate {
  int degree = 0;  ///< of p after trimming zero leading coefficients
  GramBasis basis = GramBasis::Bernstein;
  /// Lower-triangular factors (diagonal >= 0), for the polynomial as given (scaling undone). Even
  /// degree 2d: L0 is (d+1)x(d+1) for the square part, L1 is d x d for the s(1-s) part. Odd degree
  /// 2d+1: L0 is for the s part, L1 for the (1-s) part, both (d+1)x(d+1). Empty (0x0) when no
  /// certificate was built. (Degree 0: L0 is 1x1, L1 is 0x0.)
  Eigen::MatrixXd L0, L1;
  double scale = 0.0;  ///< max |monomial coefficient| of p (0 for p == 0)
  /// max_k |r_k - p_k| over the monomial coefficients, r = polynomial_from_certificate(*this).
  double max_coefficient_residual = std::numeric_limits<double>::infinity();
  /// A bound on |p - r| over [0, 1], so p(s) >= -residual_bound there: the smaller of
  /// sum_k |r_k - p_k| and the largest Bernstein coefficient of |r - p|.
  double residual_bound = std::numeric_limits<double>::infinity();
  /// Whether Ipopt found (part of) it; false: closed form throughout (degree <= 1, zero,
  /// Bernstein coefficients >= 0, possibly after the splits, or assembled from p's roots).
  bool from_ipopt = false;
  /// Factors s, 1 - s or (s - r)^2 split off at near-zero minima before solving (see
  /// CertificationOptions::deflate_near_zeros). The factors above are for p itself.
  int deflation_steps = 0;
};

struct CertificationOptions {
  /// Relative: certified when max_k |r_k - p_k| <= tolerance * max_k |p_k|.
  double tolerance = 1e-9;
  int max_iterations = 100;  ///< per Ipopt call
};

struct CertificationResult {
  std::vector<LukacsCertificate> certificates;  ///< one per input polynomial
  std::vector<bool> certified;
  std::vector<double>
      interval_minimum;  ///< pre-check: minimum of p on [0, 1] (minimum_on_interval)
  std::vector<bool> refused_by_precheck;  ///< minimum < -tolerance * scale: no certificate sought
  bool all_certified = false;
  int ipopt_calls = 0;      ///< 0, 1, or 2 with a retry
  int ipopt_variables = 0;  ///< of the first call
  int ipopt_constraints = 0;
  int ipopt_iterations = 0;    ///< summed over the calls
  double solve_seconds = 0.0;  ///< wall time of the Ipopt calls (setup of the TNLPs included)
  double wall_seconds = 0.0;   ///< wall time of the whole certification
  std::string ipopt_status = "not_called";  ///< of the first call
  std::string ipopt_linear_solver;          ///< what factored Ipopt's KKT systems (empty: no call)
  int retried_blocks = 0;                   ///< polynomials sent to the second call
  std::string retry_status = "not_called";
  /// With options.derivative_test: Ipopt's checker output and its error count (-1 if not run or
  /// not parsed).
  std::string derivative_test_report;
  int derivative_test_errors = -1;
};

/// Certify each polynomial (coefficients ascending in s) nonnegative on [0, 1], all Ipopt work in
/// one call (two if a retry is needed). Throws std::invalid_argument for non-finite coefficients or
/// a tolerance <= 0.
CertificationResult certify_nonnegative_on_unit_interval(const std::vector<Polynomial>& polys,
                                                         double tolerance);
CertificationResult certify_nonnegative_on_unit_interval(const std::vector<Polynomial>& polys,
                                                         const CertificationOptions& options);

/// The polynomial (monomial coefficients, length degree + 1) that the certificate's factors
/// represent, w0 v^T L0 L0^T v + w1 v^T L1 L1^T v (any square factors are accepted, triangular or
/// not). Throws std::invalid_argument for factors of the wrong size.
Polynomial polynomial_from_certificate(const LukacsCertificate& certificate);

}  // namespace flatsos::planner
