// Markov-Lukacs SOS certificates on [0, 1] (planner/sos_certificate.hpp): known nonnegative
// polynomials are certified (also those negative outside [0, 1], with double roots inside, with
// zeros at the ends), negative ones never are, the certificates rebuild the polynomials, and the
// NLP's derivatives pass Ipopt's derivative checker.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <iostream>
#include <limits>
#include <random>
#include <vector>

#include "flatsos/planner/numerics/sos_certificate_study.hpp"

namespace {

using flatsos::planner::CertificationStudyOptions;
using flatsos::planner::CertificationResult;
using flatsos::planner::certify_nonnegative_on_unit_interval;
using flatsos::planner::GramBasis;
using flatsos::planner::LukacsCertificate;
using flatsos::planner::minimum_on_interval;
using flatsos::planner::Polynomial;
using flatsos::planner::polynomial_from_certificate;

constexpr double kTol = 1e-9;

Polynomial poly(std::initializer_list<double> c) {
  Eigen::VectorXd v(static_cast<Eigen::Index>(c.size()));
  Eigen::Index k = 0;
  for (double x : c) v[k++] = x;
  return Polynomial(v);
}
Polynomial s_minus(double r) { return poly({-r, 1.0}); }  // s - r

// T_n(2s - 1) in monomial coefficients.
Polynomial shifted_chebyshev(int n) {
  Polynomial t0 = poly({1.0}), t1 = poly({-1.0, 2.0});
  if (n == 0) return t0;
  const Polynomial two_x = poly({-2.0, 4.0});
  for (int k = 1; k < n; ++k) {
    const Polynomial t2 = two_x * t1 - t0;
    t0 = t1;
    t1 = t2;
  }
  return t1;
}

double max_abs(const Polynomial& p) { return p.coefficients().cwiseAbs().maxCoeff(); }

// Random polynomial of the given degree with minimum on [0, 1] equal to margin * max|coefficient|.
Polynomial random_nonnegative(std::mt19937& rng, int degree, double margin) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::VectorXd c(degree + 1);
  for (int k = 0; k <= degree; ++k) c[k] = normal(rng);
  const double m = minimum_on_interval(Polynomial(c), 0.0, 1.0).value;
  c[0] += -m + margin * c.cwiseAbs().maxCoeff();
  return Polynomial(c);
}

// Everything a certificate promises about p, checked independently of the solver.
void expect_valid_certificate(const Polynomial& p, const LukacsCertificate& cert, double tol) {
  SCOPED_TRACE("degree " + std::to_string(cert.degree));
  const double scale = max_abs(p);
  ASSERT_GT(cert.L0.size() + cert.L1.size(), 0);
  // Lower triangular with a nonnegative diagonal.
  for (const Eigen::MatrixXd* L : {&cert.L0, &cert.L1}) {
    ASSERT_EQ(L->rows(), L->cols());
    for (Eigen::Index i = 0; i < L->rows(); ++i) {
      EXPECT_GE((*L)(i, i), 0.0);
      for (Eigen::Index j = i + 1; j < L->cols(); ++j) EXPECT_EQ((*L)(i, j), 0.0);
    }
  }
  // Sizes of the Lukacs form.
  const int d = cert.degree / 2;
  EXPECT_EQ(cert.L0.rows(), d + 1);
  EXPECT_EQ(cert.L1.rows(), cert.degree % 2 == 0 ? d : d + 1);
  // The rebuilt polynomial matches p coefficient by coefficient ...
  const Polynomial r = polynomial_from_certificate(cert);
  const Eigen::Index n = std::max(r.coefficients().size(), p.coefficients().size());
  Eigen::VectorXd diff = Eigen::VectorXd::Zero(n);
  diff.head(r.coefficients().size()) += r.coefficients();
  diff.head(p.coefficients().size()) -= p.coefficients();
  EXPECT_LE(diff.cwiseAbs().maxCoeff(), tol * scale);
  EXPECT_NEAR(diff.cwiseAbs().maxCoeff(), cert.max_coefficient_residual, 1e-14 * scale);
  // ... and pointwise on [0, 1], within the reported bound; the rebuilt one is >= 0 there by
  // construction (up to rounding).
  for (int i = 0; i <= 200; ++i) {
    const double s = i / 200.0;
    EXPECT_LE(std::abs(r(s) - p(s)), cert.residual_bound + 1e-13 * scale) << "s = " << s;
    EXPECT_GE(r(s), -1e-13 * scale) << "s = " << s;
    EXPECT_GE(p(s), -cert.residual_bound - 1e-13 * scale) << "s = " << s;
  }
}

void expect_all_certified(const std::vector<Polynomial>& ps, const CertificationResult& res,
                          double tol) {
  ASSERT_EQ(res.certificates.size(), ps.size());
  EXPECT_TRUE(res.all_certified) << "Ipopt: " << res.ipopt_status;
  for (std::size_t i = 0; i < ps.size(); ++i) {
    SCOPED_TRACE("polynomial " + std::to_string(i));
    EXPECT_TRUE(res.certified[i]) << "residual " << res.certificates[i].max_coefficient_residual
                                  << " scale " << res.certificates[i].scale;
    EXPECT_FALSE(res.refused_by_precheck[i]);
    expect_valid_certificate(ps[i], res.certificates[i], tol);
  }
}

// No closed form (neither the Bernstein shortcut nor the roots): what is not split off goes to
// Ipopt.
CertificationStudyOptions ipopt_only(double tol = kTol) {
  CertificationStudyOptions o;
  o.tolerance = tol;
  o.closed_form_shortcut = false;
  o.closed_form_from_roots = false;
  return o;
}
// Nothing but the L L^T program: no shortcut, no deflation of near-zero minima, no retry.
CertificationStudyOptions raw_ipopt(double tol = kTol) {
  CertificationStudyOptions o = ipopt_only(tol);
  o.deflate_near_zeros = false;
  o.retry_other_layout = false;
  return o;
}

// Nonnegative on [0, 1], negative somewhere outside: a global SOS test would refuse them.
std::vector<Polynomial> interval_only_nonnegative() {
  const Polynomial s = poly({0.0, 1.0}), one_minus_s = poly({1.0, -1.0});
  return {
      s * one_minus_s,                                             // s(1-s)
      poly({1.0, 0.0, 0.0, -1.0}),                                 // 1 - s^3
      s * s * s,                                                   // s^3
      one_minus_s * one_minus_s * one_minus_s * poly({0.1, 1.0}),  // (1-s)^3 (s+0.1)
      s * one_minus_s * s_minus(0.5) * s_minus(0.5),               // s(1-s)(s-1/2)^2
      poly({0.01, 1.0, -1.0}),                                     // 0.01 + s(1-s)
      s * s * s * s * s * one_minus_s,                             // s^5 (1-s)
      s * s_minus(0.5) * s_minus(0.5) * poly({1.2, -1.0}),         // s (s-1/2)^2 (1.2-s)
  };
}

TEST(SosCertificate, NonnegativeOnIntervalButNotGlobally) {
  const std::vector<Polynomial> ps = interval_only_nonnegative();
  for (const Polynomial& p : ps) {
    double worst_outside = std::numeric_limits<double>::infinity();
    for (double x : {-3.0, -1.0, -0.5, -0.2, 1.2, 1.5, 2.0, 3.0})
      worst_outside = std::min(worst_outside, p(x));
    EXPECT_LT(worst_outside, 0.0) << "test polynomial should be negative outside [0, 1]";
  }
  // Default options (closed form where Bernstein coefficients allow) and Ipopt for every block.
  const CertificationResult by_default = certify_nonnegative_on_unit_interval(ps, kTol);
  expect_all_certified(ps, by_default, kTol);
  const CertificationResult by_ipopt = certify_nonnegative_on_unit_interval(ps, ipopt_only());
  expect_all_certified(ps, by_ipopt, kTol);
  EXPECT_EQ(by_ipopt.ipopt_calls, 1);
  // The L L^T program alone, on those without zeros of multiplicity > 1 at an end.
  const std::vector<Polynomial> simple = {ps[0], ps[1], ps[5], ps[7]};
  const CertificationResult raw = certify_nonnegative_on_unit_interval(simple, raw_ipopt());
  expect_all_certified(simple, raw, kTol);
  for (const LukacsCertificate& c : raw.certificates) {
    EXPECT_TRUE(c.from_ipopt);
    EXPECT_EQ(c.deflation_steps, 0);
  }
}

TEST(SosCertificate, DoubleRootsInsideAndZerosAtTheEnds) {
  const Polynomial s = poly({0.0, 1.0}), one_minus_s = poly({1.0, -1.0});
  const std::vector<Polynomial> ps = {
      s_minus(0.3) * s_minus(0.3) * poly({1.0, 1.0}),             // (s-0.3)^2 (s+1)
      s_minus(0.3) * s_minus(0.3) * s_minus(0.8) * s_minus(0.8),  // two double roots
      s_minus(0.7) * s_minus(0.7) * poly({2.0, -1.0}) * s,        // zeros at 0 and 0.7
      s * poly({1.0, 0.0, 1.0}),                                  // s (1+s^2): p(0) = 0
      one_minus_s * poly({2.0, -1.0}) * poly({2.0, -1.0}),        // (1-s)(2-s)^2: p(1) = 0
      s * s * poly({3.0, -1.0, 0.5}),                             // double zero at 0
      s_minus(0.5) * s_minus(0.5) * s_minus(0.25) * s_minus(0.25) * s_minus(0.9) * s_minus(0.9) *
          poly({1.0, 0.5}),  // degree 7, 3 double roots
  };
  for (const Polynomial& p : ps) EXPECT_NEAR(minimum_on_interval(p, 0.0, 1.0).value, 0.0, 1e-12);
  for (const CertificationStudyOptions& o : {CertificationStudyOptions{}, ipopt_only()}) {
    const CertificationResult res = certify_nonnegative_on_unit_interval(ps, o);
    expect_all_certified(ps, res, kTol);
    EXPECT_LE(res.ipopt_calls, 1);
    if (!o.closed_form_shortcut) {
      for (const LukacsCertificate& c : res.certificates) EXPECT_GE(c.deflation_steps, 1);
    }
  }
  // The L L^T program alone converges on the simple zeros at the ends and the double roots
  // inside (singular but generic), to the same tolerance.
  const std::vector<Polynomial> generic = {ps[0], ps[1], ps[2], ps[3], ps[4], ps[6]};
  const CertificationResult raw = certify_nonnegative_on_unit_interval(generic, raw_ipopt());
  expect_all_certified(generic, raw, kTol);
  std::cout << "[ measure  ] 6 with exact zeros, L L^T program alone: " << raw.ipopt_iterations
            << " iterations\n";
}

// Zeros of high multiplicity at the ends and double roots close to an end: the L L^T program
// alone stalls on many of them (full or triangular factors); the split at the minimum fixes it.
TEST(SosCertificate, NearZeroMinimaAreSplitOff) {
  const Polynomial s = poly({0.0, 1.0}), one_minus_s = poly({1.0, -1.0});
  const Polynomial g =
      poly({0.161, -0.8, 1.0});  // (s-0.4)^2 + 0.001: negative Bernstein coefficient
  std::vector<Polynomial> ps;
  for (int k0 = 0; k0 <= 3; ++k0)
    for (int k1 = 0; k1 <= 3; ++k1) {
      Polynomial p = g;
      for (int k = 0; k < k0; ++k) p = p * s;
      for (int k = 0; k < k1; ++k) p = p * one_minus_s;
      ps.push_back(p);
    }
  ps.push_back(poly({4.2328489068339976e-05, -0.010039710383824976,
                     0.59531881960366595}));  // double root at 0.0084
  ps.push_back(s_minus(0.5) * s_minus(0.5) * s_minus(0.5) * s_minus(0.5) * g);  // quadruple root
  ps.push_back(s_minus(0.2) * s_minus(0.2) * s_minus(0.9) * s_minus(0.9) * g +
               poly({1e-6}));              // two near-zero minima
  ps.push_back(s * s * g + poly({1e-5}));  // near-zero end
  const CertificationResult res = certify_nonnegative_on_unit_interval(ps, ipopt_only());
  expect_all_certified(ps, res, kTol);
  EXPECT_LE(res.ipopt_calls, 1);
  for (std::size_t i = 1; i < ps.size(); ++i)
    EXPECT_GE(res.certificates[i].deflation_steps, 1) << i;
  // Splits with a remainder (minimum 1e-6 or 1e-5, not zero) are exact: nothing is dropped.
  for (std::size_t i = ps.size() - 2; i < ps.size(); ++i)
    EXPECT_LE(res.certificates[i].max_coefficient_residual, 1e-13 * res.certificates[i].scale) << i;
}

TEST(SosCertificate, StrictlyPositiveDegreesZeroToEight) {
  std::vector<Polynomial> ps;
  for (int n = 0; n <= 8; ++n) ps.push_back(shifted_chebyshev(n) + poly({1.5}));  // min 0.5
  ps[0] = poly({2.0});
  // T_n(2s-1) + 1.5 has negative Bernstein coefficients for n >= 2: those need Ipopt when the
  // roots are not used, and by default none does.
  CertificationStudyOptions bernstein_then_ipopt;
  bernstein_then_ipopt.closed_form_from_roots = false;
  for (const CertificationStudyOptions& o : {bernstein_then_ipopt, CertificationStudyOptions{}}) {
    const CertificationResult res = certify_nonnegative_on_unit_interval(ps, o);
    expect_all_certified(ps, res, kTol);
    EXPECT_EQ(res.ipopt_calls, o.closed_form_from_roots ? 0 : 1);
    for (int n = 0; n <= 8; ++n) {
      EXPECT_EQ(res.certificates[static_cast<std::size_t>(n)].degree, n);
      EXPECT_EQ(res.certificates[static_cast<std::size_t>(n)].from_ipopt, !o.closed_form_from_roots && n >= 2)
          << "degree " << n;
    }
  }
  // Every basis gives a valid certificate (cross-check of the three coefficient maps).
  for (GramBasis basis : {GramBasis::Bernstein, GramBasis::Chebyshev, GramBasis::Monomial}) {
    SCOPED_TRACE(flatsos::planner::gram_basis_name(basis));
    CertificationStudyOptions o = ipopt_only();
    o.basis = basis;
    expect_all_certified(ps, certify_nonnegative_on_unit_interval(ps, o), kTol);
  }
  // Lower-triangular variables (the textbook recipe) also work on strictly positive ones.
  CertificationStudyOptions tri = ipopt_only();
  tri.triangular_factors = true;
  expect_all_certified(ps, certify_nonnegative_on_unit_interval(ps, tri), kTol);
}

TEST(SosCertificate, RandomBatchOfFortyInOneCall) {
  std::mt19937 rng(20240521);
  const double margins[] = {0.0, 1e-6, 1e-3, 0.1};
  std::vector<Polynomial> ps;
  for (int i = 0; i < 40; ++i) ps.push_back(random_nonnegative(rng, 2 + i % 7, margins[i % 4]));
  const CertificationResult res = certify_nonnegative_on_unit_interval(ps, ipopt_only());
  expect_all_certified(ps, res, kTol);
  EXPECT_EQ(res.ipopt_calls, 1);
  EXPECT_LE(res.ipopt_iterations, 60);
  std::cout << "[ measure  ] 40 random, degrees 2..8, margins {0,1e-6,1e-3,0.1}: "
            << res.ipopt_iterations << " Ipopt iterations, " << res.solve_seconds * 1e3 << " ms ("
            << res.ipopt_variables << " variables, " << res.ipopt_constraints << " constraints)\n";
  // Default options: the closed forms (Bernstein, then the roots) take every one.
  const CertificationResult by_default = certify_nonnegative_on_unit_interval(ps, kTol);
  expect_all_certified(ps, by_default, kTol);
  EXPECT_EQ(by_default.ipopt_calls, 0);
}

// p = c prod(factors), each factor >= 0 on [0, 1]: real roots below 0 and above 1, double roots
// inside, roots at the ends, complex pairs near and far from [0, 1], and the same shifted by a
// minimum of 1e-12 * scale (two real roots, a hair apart, become a complex pair).
std::vector<Polynomial> products_of_root_factors(std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Polynomial> ps;
  for (int i = 0; i < 120; ++i) {
    Polynomial p = poly({0.1 + 10.0 * unit(rng)});
    const int factors = 1 + i % 5;
    for (int k = 0; k < factors; ++k) {
      switch ((i + k) % 6) {
        case 0: p = p * poly({3.0 * unit(rng), 1.0}); break;                    // s + |r|
        case 1: p = p * poly({1.0 + 3.0 * unit(rng), -1.0}); break;             // r - s, r >= 1
        case 2: { const double m = unit(rng); p = p * s_minus(m) * s_minus(m); break; }  // (s - m)^2
        case 3: p = p * (i % 2 == 0 ? poly({0.0, 1.0}) : poly({1.0, -1.0})); break;       // s or 1 - s
        case 4: { const double a = unit(rng), b = 1e-3 + 0.5 * unit(rng);                // (s - a)^2 + b^2
                  p = p * (s_minus(a) * s_minus(a) + poly({b * b})); break; }
        default: { const double a = 4.0 * unit(rng) - 2.0, b = 2.0 * unit(rng);
                   p = p * (s_minus(a) * s_minus(a) + poly({b * b})); break; }
      }
    }
    if (i % 3 == 2) p = p + poly({1e-12 * max_abs(p)});
    ps.push_back(p);
  }
  return ps;
}

// The certificate assembled from the roots (the constructive proof of Lukacs' theorem) certifies
// every product of nonnegative factors without Ipopt, in each basis; without it Ipopt is needed.
TEST(SosCertificate, ProductsOfRootFactorsAreCertifiedFromTheirRoots) {
  std::mt19937 rng(1729);
  const std::vector<Polynomial> ps = products_of_root_factors(rng);
  for (GramBasis basis : {GramBasis::Bernstein, GramBasis::Chebyshev, GramBasis::Monomial}) {
    SCOPED_TRACE(flatsos::planner::gram_basis_name(basis));
    CertificationStudyOptions o;
    o.basis = basis;
    const CertificationResult res = certify_nonnegative_on_unit_interval(ps, o);
    expect_all_certified(ps, res, kTol);
    EXPECT_EQ(res.ipopt_calls, 0);
    double worst = 0.0;
    for (const LukacsCertificate& c : res.certificates) worst = std::max(worst, c.max_coefficient_residual / c.scale);
    std::cout << "[ measure  ] 120 products of root factors, degrees 1..11, " << flatsos::planner::gram_basis_name(basis)
              << ": largest relative residual " << worst << "\n";
  }
  CertificationStudyOptions without_roots;
  without_roots.closed_form_from_roots = false;
  EXPECT_EQ(certify_nonnegative_on_unit_interval(ps, without_roots).ipopt_calls, 1);
}

// Coefficients of extreme range (roots near 1e-150 or 1e150): positive on [0, 1], certified,
// and each certificate valid (the roots' construction gives up on non-finite roots).
TEST(SosCertificate, ExtremeCoefficientsAreCertifiedCorrectly) {
  const std::vector<Polynomial> ps = {
      poly({1e-300, 0.0, 1e300}),        // 1e300 s^2 + 1e-300
      poly({1e150, -1.0, 1e-150}),       // complex roots of size 1e150
      poly({1e-200, 1e-200, 0.0, 1e200}),  // 1e200 s^3 + 1e-200 (s + 1)
      poly({0.25 + 1e-300, -1.0, 1.0}),    // (s - 1/2)^2 + 1e-300: a negative Bernstein coefficient
      poly({1e300, -1e300, 1e300, 1e300}),
  };
  const CertificationResult res = certify_nonnegative_on_unit_interval(ps, kTol);
  for (std::size_t i = 0; i < ps.size(); ++i) {
    SCOPED_TRACE("polynomial " + std::to_string(i));
    EXPECT_TRUE(res.certified[i]);  // each is > 0 on [0, 1]
    if (res.certified[i]) expect_valid_certificate(ps[i], res.certificates[i], kTol);
  }
}

std::vector<Polynomial> negative_somewhere();

// The roots never certify what is negative somewhere on [0, 1], even without the pre-check:
// the signs of the factors or the residual give it away.
TEST(SosCertificate, TheRootsDoNotCertifyNegativePolynomials) {
  CertificationStudyOptions o;
  o.precheck = false;
  o.deflate_near_zeros = false;
  o.max_iterations = 30;
  const std::vector<Polynomial> ps = negative_somewhere();
  const CertificationResult res = certify_nonnegative_on_unit_interval(ps, o);
  for (std::size_t i = 0; i < ps.size(); ++i) {
    EXPECT_FALSE(res.certified[i]) << i;
    EXPECT_FALSE(res.certificates[i].L0.size() > 0 && !res.certificates[i].from_ipopt &&
                 res.certificates[i].max_coefficient_residual <= kTol * res.certificates[i].scale)
        << i;
  }
}

// Reports (does not time-test) the batches the planner needs: 40 quartics, 40 sextics, by the
// L L^T program alone and by the default pipeline without the closed-form shortcut.
TEST(SosCertificate, FortyQuarticsAndFortySextics) {
  for (int degree : {4, 6}) {
    for (double margin : {1e-3, 0.0}) {
      std::mt19937 rng(7u + static_cast<unsigned>(degree));
      std::vector<Polynomial> ps;
      for (int i = 0; i < 40; ++i) ps.push_back(random_nonnegative(rng, degree, margin));
      const CertificationResult raw = certify_nonnegative_on_unit_interval(ps, raw_ipopt());
      expect_all_certified(ps, raw, kTol);
      EXPECT_EQ(raw.ipopt_calls, 1);
      const CertificationResult res = certify_nonnegative_on_unit_interval(ps, ipopt_only());
      expect_all_certified(ps, res, kTol);
      std::cout << "[ measure  ] 40 of degree " << degree << ", min = " << margin
                << " * scale: L L^T alone " << raw.ipopt_iterations << " iterations, "
                << raw.solve_seconds * 1e3 << " ms; with the splits " << res.ipopt_iterations
                << " iterations, " << res.solve_seconds * 1e3 << " ms\n";
    }
  }
}

std::vector<Polynomial> negative_somewhere() {
  std::mt19937 rng(99);
  std::vector<Polynomial> ps = {
      poly({-1.0}),
      s_minus(0.5),                                 // negative on [0, 0.5)
      s_minus(0.3) * s_minus(0.3) + poly({-1e-4}),  // just below zero around 0.3
      s_minus(0.5) * s_minus(0.5) * poly({1.0, 1.0}) + poly({-1e-6}),
      poly({-0.3, 1.0, -1.0}),                      // s(1-s) - 0.3 < 0 everywhere
      poly({0.0, 1.0, 0.0, -2.0}),                  // s - 2 s^3: negative near 1
      poly({1e-3, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0}),  // dips below 0 inside
  };
  for (int degree = 2; degree <= 8; ++degree) ps.push_back(random_nonnegative(rng, degree, -1e-3));
  return ps;
}

TEST(SosCertificate, NegativeSomewhereIsRefused) {
  const std::vector<Polynomial> ps = negative_somewhere();
  for (const Polynomial& p : ps) ASSERT_LT(minimum_on_interval(p, 0.0, 1.0).value, -1e-7);
  // The pre-check refuses them all without Ipopt.
  const CertificationResult res = certify_nonnegative_on_unit_interval(ps, kTol);
  EXPECT_FALSE(res.all_certified);
  EXPECT_EQ(res.ipopt_calls, 0);
  for (std::size_t i = 0; i < ps.size(); ++i) {
    EXPECT_FALSE(res.certified[i]) << i;
    EXPECT_TRUE(res.refused_by_precheck[i]) << i;
  }
  // Without the pre-check, Ipopt alone (infeasible, or a residual that stays too large) must
  // not certify any of them either.
  CertificationStudyOptions no_precheck = ipopt_only();
  no_precheck.precheck = false;
  no_precheck.max_iterations = 100;
  const CertificationResult raw = certify_nonnegative_on_unit_interval(ps, no_precheck);
  std::cout << "[ measure  ] negative batch without pre-check: " << raw.ipopt_status << " after "
            << raw.ipopt_iterations << " iterations\n";
  for (std::size_t i = 0; i < ps.size(); ++i) {
    EXPECT_FALSE(raw.certified[i]) << i;
    if (raw.certificates[i].L0.size() > 0) {
      EXPECT_GT(raw.certificates[i].max_coefficient_residual, kTol * raw.certificates[i].scale);
    }
  }
}

TEST(SosCertificate, MixedBatchCertifiesOnlyTheNonnegative) {
  std::vector<Polynomial> good = interval_only_nonnegative();
  const std::vector<Polynomial> bad = negative_somewhere();
  std::vector<Polynomial> ps;
  for (std::size_t i = 0; i < std::max(good.size(), bad.size()); ++i) {
    if (i < good.size()) ps.push_back(good[i]);
    if (i < bad.size()) ps.push_back(bad[i]);
  }
  const CertificationResult res = certify_nonnegative_on_unit_interval(ps, ipopt_only());
  EXPECT_FALSE(res.all_certified);
  EXPECT_EQ(res.ipopt_calls, 1);
  for (std::size_t i = 0; i < ps.size(); ++i) {
    const bool nonnegative = minimum_on_interval(ps[i], 0.0, 1.0).value >= -1e-12;
    EXPECT_EQ(res.certified[i], nonnegative) << i;
    if (nonnegative) expect_valid_certificate(ps[i], res.certificates[i], kTol);
  }
}

TEST(SosCertificate, WithinToleranceOfZero) {
  // Minimum -0.1 tol * scale: certified (through p + delta; the residual shows delta).
  // Minimum -10 tol * scale: refused.
  const Polynomial base = s_minus(0.4) * s_minus(0.4) * poly({1.0, 1.0});
  const double scale = max_abs(base);
  const Polynomial slightly = base + poly({-0.1 * kTol * scale});
  const Polynomial clearly = base + poly({-10.0 * kTol * scale});
  const CertificationResult res =
      certify_nonnegative_on_unit_interval({slightly, clearly}, ipopt_only());
  EXPECT_TRUE(res.certified[0]);
  EXPECT_GE(res.certificates[0].max_coefficient_residual, 0.1 * kTol * scale * 0.99);
  expect_valid_certificate(slightly, res.certificates[0], kTol);
  EXPECT_FALSE(res.certified[1]);
  EXPECT_TRUE(res.refused_by_precheck[1]);
}

TEST(SosCertificate, TrivialCasesAndTrimming) {
  const std::vector<Polynomial> ps = {
      poly({0.0}),                  // zero
      poly({0.0, 0.0, 0.0}),        // zero with zero top coefficients
      poly({3.0}),                  // constant
      poly({1.0, -1.0}),            // 1 - s: zero at 1
      poly({0.0, 2.0, 0.0, 0.0}),   // 2 s, stored with degree 3
      poly({1.0, -1.0, 0.0, 0.0}),  // 1 - s, stored with degree 3
      poly({0.6, -2.0, 2.0, 0.0}),  // degree 2 stored as 3 (minimum 0.1, Bernstein b1 < 0)
  };
  const CertificationResult res = certify_nonnegative_on_unit_interval(ps, ipopt_only());
  EXPECT_TRUE(res.all_certified);
  const int degrees[] = {0, 0, 0, 1, 1, 1, 2};
  for (std::size_t i = 0; i < ps.size(); ++i) {
    EXPECT_TRUE(res.certified[i]) << i;
    EXPECT_EQ(res.certificates[i].degree, degrees[i]) << i;
    EXPECT_EQ(res.certificates[i].from_ipopt, degrees[i] >= 2) << i;
    if (i >= 2) expect_valid_certificate(ps[i], res.certificates[i], kTol);
  }
  // Closed forms are exact.
  EXPECT_EQ(res.certificates[2].L0(0, 0), std::sqrt(3.0));
  EXPECT_EQ(res.certificates[3].max_coefficient_residual, 0.0);
  // Negative constant and negative linear ones are refused.
  const CertificationResult neg =
      certify_nonnegative_on_unit_interval({poly({-1e-3}), poly({1.0, -1.01})}, kTol);
  EXPECT_FALSE(neg.certified[0]);
  EXPECT_FALSE(neg.certified[1]);
  // Empty input.
  const CertificationResult none = certify_nonnegative_on_unit_interval({}, kTol);
  EXPECT_TRUE(none.all_certified);
  EXPECT_EQ(none.ipopt_calls, 0);
}

TEST(SosCertificate, ReconstructionFromHandMadeFactors) {
  // Degree 2, Bernstein: L0 = I (basis 1-s, s), L1 = [1]:
  // (1-s)^2 + s^2 + s(1-s) = 1 - s + s^2.
  LukacsCertificate c;
  c.degree = 2;
  c.basis = GramBasis::Bernstein;
  c.L0 = Eigen::MatrixXd::Identity(2, 2);
  c.L1 = Eigen::MatrixXd::Ones(1, 1);
  const Eigen::VectorXd r = polynomial_from_certificate(c).coefficients();
  ASSERT_EQ(r.size(), 3);
  EXPECT_NEAR(r[0], 1.0, 1e-15);
  EXPECT_NEAR(r[1], -1.0, 1e-15);
  EXPECT_NEAR(r[2], 1.0, 1e-15);
  // Degree 3, monomial basis v = (1, s): L0 = [[1,0],[0,1]] for s(1 + s^2), L1 = 0:
  // s + s^3.
  c.degree = 3;
  c.basis = GramBasis::Monomial;
  c.L0 = Eigen::MatrixXd::Identity(2, 2);
  c.L1 = Eigen::MatrixXd::Zero(2, 2);
  const Eigen::VectorXd r3 = polynomial_from_certificate(c).coefficients();
  ASSERT_EQ(r3.size(), 4);
  EXPECT_NEAR(r3[0], 0.0, 1e-15);
  EXPECT_NEAR(r3[1], 1.0, 1e-15);
  EXPECT_NEAR(r3[2], 0.0, 1e-15);
  EXPECT_NEAR(r3[3], 1.0, 1e-15);
  // Same polynomial in the Chebyshev basis: v = (1, 2s - 1), so s = (v0 + v1)/2:
  // L0 = [[1/2, 0], [1/2, 0]] gives s * s^2 = s^3; L1 = 0.
  c.basis = GramBasis::Chebyshev;
  c.L0 << 0.5, 0.0, 0.5, 0.0;
  const Eigen::VectorXd rc = polynomial_from_certificate(c).coefficients();
  EXPECT_NEAR(rc[3], 1.0, 1e-15);
  EXPECT_NEAR(rc.head(3).cwiseAbs().maxCoeff(), 0.0, 1e-15);
  // Wrong sizes are refused.
  c.L1 = Eigen::MatrixXd::Zero(1, 1);
  EXPECT_THROW(polynomial_from_certificate(c), std::invalid_argument);
}

TEST(SosCertificate, InvalidInputThrows) {
  EXPECT_THROW(certify_nonnegative_on_unit_interval({poly({1.0})}, 0.0), std::invalid_argument);
  EXPECT_THROW(certify_nonnegative_on_unit_interval({poly({1.0})}, -1.0), std::invalid_argument);
  EXPECT_THROW(certify_nonnegative_on_unit_interval({poly({1.0, std::nan("")})}, kTol),
               std::invalid_argument);
}

TEST(SosCertificate, IpoptDerivativeCheckerFindsNoError) {
  const std::vector<Polynomial> ps = {
      s_minus(0.3) * s_minus(0.3) * poly({1.0, 1.0}),  // degree 3
      shifted_chebyshev(4) + poly({1.5}),              // degree 4
      shifted_chebyshev(5) + poly({1.2}),              // degree 5
  };
  struct Case {
    const char* name;
    bool triangular;
    double proximal;
    GramBasis basis;
  };
  for (const Case& k : {Case{"full", false, 0.0, GramBasis::Bernstein},
                        Case{"triangular+proximal", true, 0.3, GramBasis::Bernstein},
                        Case{"chebyshev", false, 0.1, GramBasis::Chebyshev}}) {
    SCOPED_TRACE(k.name);
    CertificationStudyOptions o = raw_ipopt();
    o.derivative_test = true;
    o.triangular_factors = k.triangular;
    o.proximal_weight = k.proximal;
    o.basis = k.basis;
    const CertificationResult res = certify_nonnegative_on_unit_interval(ps, o);
    EXPECT_NE(res.derivative_test_report.find("Starting derivative checker for second derivatives"),
              std::string::npos);
    EXPECT_EQ(res.derivative_test_errors, 0) << res.derivative_test_report;
    EXPECT_TRUE(res.all_certified);
  }
}

}  // namespace
