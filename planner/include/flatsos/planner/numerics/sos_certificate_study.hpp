#pragma once
// Knobs for studying the Lukacs certificate method (tests, measurements, diagnosis), kept out of
// the production CertificationOptions. The defaults are the measured best and are what
// certify_nonnegative_on_unit_interval(polys, CertificationOptions) uses; the measurements are in
// docs/method/sos_certificates.md.

#include <vector>

#include "flatsos/planner/numerics/sos_certificate.hpp"

namespace flatsos::planner {

struct CertificationStudyOptions : CertificationOptions {
  GramBasis basis = GramBasis::Bernstein;
  /// Diagonal Bernstein certificate without Ipopt when all Bernstein coefficients are >= 0.
  bool closed_form_shortcut = true;
  /// Otherwise, before Ipopt: the certificate assembled from p's roots (lukacs_roots.hpp), kept
  /// when its residual passes. false: Ipopt certifies what the Bernstein shortcut does not.
  bool closed_form_from_roots = true;
  /// Refuse, without Ipopt, polynomials whose minimum on [0,1] is < -tolerance * scale. Only
  /// tests switch it off (to see that Ipopt alone refuses negative polynomials).
  bool precheck = true;
  /// Objective 0.5 w ||x - x_start||^2 over the (normalized) factor entries: a proximal term that
  /// picks one point of the Gram family without biasing anything outside (0 = pure feasibility).
  double proximal_weight = 0.0;
  /// Ipopt's variables: full square factors (default) or lower-triangular ones. The returned
  /// factors are lower triangular either way (QR of the full factor).
  bool triangular_factors = false;
  /// While the minimum of p on [0, 1] is <= deflation_threshold * max|Bernstein coefficient|,
  /// split p at its global minimizer r: p = w q + rest, w = s (r = 0), 1 - s (r = 1) or (s - r)^2,
  /// rest of degree <= 1 and >= 0 (or negligible). q is certified (closed form or Ipopt), then
  /// the certificate of p is assembled exactly: w's multiplication matrix conjugates the Grams
  /// and rest's diagonal Bernstein Gram is added. The L L^T program is nearly singular at such
  /// minima (Ipopt stalls on zeros of multiplicity >= 2 at an end, or double roots near an end).
  bool deflate_near_zeros = true;
  double deflation_threshold = 1e-3;
  /// Blocks left uncertified by the first call get a second call (all together) with the other
  /// factor layout: full factors fail on some zeros of high multiplicity at the ends, triangular
  /// ones on some generic double roots.
  bool retry_other_layout = true;
  /// Bounds L_ii >= 0 (removes the sign symmetry of each column).
  bool nonnegative_diagonal = false;
  /// Floor, relative to the largest, of the Bernstein coefficients used for the diagonal start.
  double start_floor = 0.01;
  /// Run Ipopt's derivative checker ("second-order") at a perturbed start; the report is returned.
  bool derivative_test = false;
  /// Ipopt's print_level (0: silent), for diagnosis.
  int ipopt_print_level = 0;
};


/// Certification with every knob of the method exposed.
CertificationResult certify_nonnegative_on_unit_interval(const std::vector<Polynomial>& polys,
                                                         const CertificationStudyOptions& options);

}  // namespace flatsos::planner
