#include "flatsos/planner/numerics/sos_certificate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "flatsos/planner/numerics/sos_certificate_study.hpp"
#include "flatsos/planner/numerics/ipopt_linear_solver.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "numerics/lukacs_algebra.hpp"
#include "numerics/lukacs_basis.hpp"
#include "numerics/lukacs_nlp.hpp"
#include "numerics/lukacs_roots.hpp"

// Why the defaults are what they are (basis, factor layout, start, objective, splits):
// docs/method/sos_certificates.md.

namespace flatsos::planner {

using namespace detail;
using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

std::string gram_basis_name(GramBasis basis) {
  switch (basis) {
    case GramBasis::Bernstein:
      return "bernstein";
    case GramBasis::Chebyshev:
      return "chebyshev";
    case GramBasis::Monomial:
      return "monomial";
  }
  return "unknown";
}

Polynomial polynomial_from_certificate(const LukacsCertificate& cert) {
  if (cert.degree < 0) throw std::invalid_argument("Lukacs certificate: negative degree");
  const LukacsOperator op = make_operator(cert.basis, cert.degree);
  if (cert.L0.rows() != op.m0 || cert.L0.cols() != op.m0 || cert.L1.rows() != op.m1 ||
      cert.L1.cols() != op.m1)
    throw std::invalid_argument("Lukacs certificate: factor sizes do not match degree " +
                                std::to_string(cert.degree));
  const VectorXd fam =
      apply_operator(op, cert.L0 * cert.L0.transpose(), cert.L1 * cert.L1.transpose());
  return Polynomial(to_monomial(cert.basis, cert.degree) * fam);
}

CertificationResult certify_nonnegative_on_unit_interval(const std::vector<Polynomial>& polys,
                                                         double tolerance) {
  CertificationStudyOptions options;
  options.tolerance = tolerance;
  return certify_nonnegative_on_unit_interval(polys, options);
}

CertificationResult certify_nonnegative_on_unit_interval(const std::vector<Polynomial>& polys,
                                                         const CertificationOptions& production) {
  CertificationStudyOptions options;
  static_cast<CertificationOptions&>(options) = production;
  return certify_nonnegative_on_unit_interval(polys, options);
}

namespace {

// Closed form: diagonal Bernstein Gram (exact when the Bernstein coefficients are >= 0; always
// used for degree <= 1, where the Bernstein coefficients are p(0), p(1)).
bool closed_form_certifies(const VectorXd& q, double scale, const CertificationStudyOptions& options) {
  return scale == 0.0 || q.size() <= 2 ||
         (options.closed_form_shortcut && from_monomial(GramBasis::Bernstein, q).minCoeff() >= 0.0);
}

LukacsCertificate finished(const LukacsCertificate& qc, const std::vector<DeflationStep>& steps, double scale,
                           const VectorXd& p) {
  LukacsCertificate full = undo_deflation(qc, steps);
  full.scale = scale;
  full.deflation_steps = static_cast<int>(steps.size());
  fill_residual(full, p);
  return full;
}

// The certificate of p from a closed form of q (p with `steps` split off): the diagonal Bernstein
// Gram when q's Bernstein coefficients are >= 0 (exact), else the one assembled from q's roots
// when its residual passes (the roots of q are computed, not exact). None: Ipopt's turn.
std::optional<LukacsCertificate> closed_form(const VectorXd& q, const std::vector<DeflationStep>& steps, double scale,
                                             const VectorXd& p, const CertificationStudyOptions& options) {
  if (closed_form_certifies(q, scale, options)) return finished(bernstein_diagonal_certificate(q), steps, scale, p);
  if (!options.closed_form_from_roots) return std::nullopt;
  const std::optional<LukacsCertificate> from_roots = certificate_from_roots(q, options.basis);
  if (!from_roots) return std::nullopt;
  LukacsCertificate cert = finished(*from_roots, steps, scale, p);
  if (!(cert.max_coefficient_residual <= options.tolerance * scale)) return std::nullopt;
  return cert;
}

// The Ipopt block for q (polynomial ip after deflation). A computed minimum slightly below zero
// (within the tolerance, else refused before) would make the exact problem infeasible and Ipopt
// would iterate to its limit: the block certifies q + delta instead, and delta counts in the
// residual against p.
Block ipopt_block(std::size_t ip, const Deflation& defl, double interval_minimum, double tol,
                  const CertificationStudyOptions& options) {
  const VectorXd& q = defl.q;
  const int nq = static_cast<int>(q.size()) - 1;
  const double q_scale = q.cwiseAbs().maxCoeff();
  VectorXd target_poly = q;
  if (options.precheck) {
    const double q_min = defl.steps.empty() ? interval_minimum : minimum_on_interval(Polynomial(q), 0.0, 1.0).value;
    if (q_min < 0.0) target_poly[0] += -q_min + 0.01 * tol * q_scale;
  }
  Block b;
  b.poly = ip;
  b.deflation = defl.steps;
  b.op = make_operator(options.basis, nq);
  const VectorXd fam = from_monomial(options.basis, target_poly);
  b.normalization = fam.cwiseAbs().maxCoeff();
  b.target = fam / b.normalization;
  b.weight = to_monomial(options.basis, nq).cwiseAbs().rowwise().sum().maxCoeff() * b.normalization / q_scale;
  // Start: the diagonal Bernstein Gram of the normalized Bernstein coefficients, clipped from
  // below at start_floor times the largest.
  const VectorXd beta_t = from_monomial(GramBasis::Bernstein, target_poly);
  const double bmax = beta_t.cwiseAbs().maxCoeff();
  const VectorXd beta_start = (beta_t / b.normalization).cwiseMax(options.start_floor * bmax / b.normalization);
  const auto [l0, l1] = bernstein_diagonal(make_operator(GramBasis::Bernstein, nq), beta_start);
  b.start_L0 = convert_diagonal_factor(options.basis, l0);
  b.start_L1 = convert_diagonal_factor(options.basis, l1);
  return b;
}

// Polynomial ip: refused by the precheck, certified in closed form (after deflation), or left to
// Ipopt (its block appended to `blocks`).
void prepare_polynomial(std::size_t ip, const Polynomial& poly, const CertificationStudyOptions& options,
                        CertificationResult& res, std::vector<Block>& blocks) {
  const double tol = options.tolerance;
  const VectorXd& c = poly.coefficients();
  LukacsCertificate& cert = res.certificates[ip];
  const double scale = c.cwiseAbs().maxCoeff();
  cert.scale = scale;
  Index len = c.size();
  while (len > 1 && std::abs(c[len - 1]) <= std::numeric_limits<double>::epsilon() * scale) --len;
  cert.degree = static_cast<int>(len) - 1;
  const VectorXd pc = c.head(len);
  res.interval_minimum[ip] = minimum_on_interval(Polynomial(pc), 0.0, 1.0).value;
  if (options.precheck && res.interval_minimum[ip] < -tol * scale) {
    res.refused_by_precheck[ip] = true;
    cert.L0.resize(0, 0);
    cert.L1.resize(0, 0);
    return;
  }
  if (auto closed = closed_form(pc, {}, scale, c, options)) {
    cert = *closed;
    return;
  }
  // Near-zero minima are split off exactly (at the global minimum: s, 1 - s or (s - r)^2, the
  // small remainder certified apart): the L L^T program is nearly singular there, and the roots
  // of a cluster are too inexact for the closed form.
  Deflation defl;
  defl.q = pc;
  if (options.deflate_near_zeros) defl = deflate(pc, options.deflation_threshold, 0.01 * tol * scale);
  if (!defl.steps.empty())
    if (auto closed = closed_form(defl.q, defl.steps, scale, c, options)) {
      cert = *closed;
      return;
    }
  blocks.push_back(ipopt_block(ip, defl, res.interval_minimum[ip], tol, options));
}

// Ipopt's factors of each block as certificates of their polynomials, kept where they beat the
// certificate a polynomial has.
void certify_blocks(const std::vector<Block>& bs, const IpoptRun& run, const std::vector<Polynomial>& polys,
                    const CertificationStudyOptions& options, CertificationResult& res) {
  if (run.factors.size() != bs.size()) return;  // Ipopt returned no point
  for (std::size_t bi = 0; bi < bs.size(); ++bi) {
    const Block& b = bs[bi];
    LukacsCertificate cand;
    cand.degree = b.op.degree;
    cand.basis = options.basis;
    const double root = std::sqrt(b.normalization);
    cand.L0 = lower_triangular_factor(run.factors[bi].first * root);
    cand.L1 = lower_triangular_factor(run.factors[bi].second * root);
    cand = undo_deflation(cand, b.deflation);
    cand.scale = res.certificates[b.poly].scale;
    cand.deflation_steps = static_cast<int>(b.deflation.size());
    cand.from_ipopt = true;
    fill_residual(cand, polys[b.poly].coefficients());
    LukacsCertificate& cert = res.certificates[b.poly];
    if (!cert.from_ipopt || !(cert.max_coefficient_residual <= cand.max_coefficient_residual)) cert = cand;
  }
}

// All blocks in one Ipopt call; those it leaves uncertified get one more chance, all in one more
// call, with the other factor layout (they fail on different polynomials).
void solve_blocks(std::vector<Block>& blocks, const std::vector<Polynomial>& polys,
                  const CertificationStudyOptions& options, CertificationResult& res) {
  const double tol = options.tolerance;
  const Stopwatch ipopt_wall;
  for (const Block& b : blocks) {  // until Ipopt gives something better
    LukacsCertificate& cert = res.certificates[b.poly];
    cert.L0.resize(0, 0);
    cert.L1.resize(0, 0);
    cert.from_ipopt = false;
  }
  FactorLayout layout;
  layout.full = !options.triangular_factors;
  const IpoptRun first = run_ipopt(blocks, layout, options, tol, options.derivative_test);
  certify_blocks(blocks, first, polys, options, res);
  res.ipopt_calls = 1;
  res.ipopt_status = first.status;
  add_linear_solver_name(res.ipopt_linear_solver, first.linear_solver);
  res.ipopt_iterations = first.iterations;
  res.ipopt_variables = first.variables;
  res.ipopt_constraints = first.constraints;
  res.derivative_test_report = first.derivative_report;
  res.derivative_test_errors = first.derivative_errors;
  std::vector<Block> again;
  if (options.retry_other_layout)
    for (const Block& b : blocks)
      if (!(res.certificates[b.poly].max_coefficient_residual <= tol * res.certificates[b.poly].scale)) again.push_back(b);
  if (!again.empty()) {
    FactorLayout other = layout;
    other.full = !layout.full;
    const IpoptRun second = run_ipopt(again, other, options, tol, false);
    certify_blocks(again, second, polys, options, res);
    res.ipopt_calls = 2;
    res.retried_blocks = static_cast<int>(again.size());
    res.retry_status = second.status;
    res.ipopt_iterations += second.iterations;
    add_linear_solver_name(res.ipopt_linear_solver, second.linear_solver);
  }
  res.solve_seconds = ipopt_wall.seconds();
}

}  // namespace

CertificationResult certify_nonnegative_on_unit_interval(const std::vector<Polynomial>& polys,
                                                         const CertificationStudyOptions& options) {
  const Stopwatch wall;
  const double tol = options.tolerance;
  if (!(tol > 0.0) || !std::isfinite(tol)) throw std::invalid_argument("SOS certificate: tolerance must be > 0");
  for (const Polynomial& p : polys)
    if (!p.coefficients().allFinite())
      throw std::invalid_argument("SOS certificate: polynomial with non-finite coefficients");
  const std::size_t np = polys.size();
  CertificationResult res;
  res.certificates.resize(np);
  res.certified.assign(np, false);
  res.interval_minimum.assign(np, 0.0);
  res.refused_by_precheck.assign(np, false);
  std::vector<Block> blocks;
  for (std::size_t ip = 0; ip < np; ++ip) prepare_polynomial(ip, polys[ip], options, res, blocks);
  if (!blocks.empty()) solve_blocks(blocks, polys, options, res);
  res.all_certified = true;
  for (std::size_t ip = 0; ip < np; ++ip) {
    const LukacsCertificate& cert = res.certificates[ip];
    res.certified[ip] = !res.refused_by_precheck[ip] && cert.L0.size() + cert.L1.size() > 0 &&
                        cert.max_coefficient_residual <= tol * cert.scale;
    if (cert.scale == 0.0) res.certified[ip] = true;  // p == 0
    res.all_certified = res.all_certified && res.certified[ip];
  }
  res.wall_seconds = wall.seconds();
  return res;
}

}  // namespace flatsos::planner
