// Clamped B-splines, by their laws: nonnegative partition of unity, clamped ends, derivatives
// against finite differences, exact reproduction of polynomials of their degree, and
// continuity of exactly the orders below the degree at interior knots.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "flatsos/planner/numerics/bspline.hpp"
#include "flatsos/planner/numerics/polynomial.hpp"
#include "flatsos/planner/numerics/spline_trajectory.hpp"

namespace fpl = flatsos::planner;

namespace {
// The k-th derivative (1/h^k scaled) of the span polynomial at s, from the power matrix.
double span_derivative(const fpl::BSplineBasis& b, int span, double s, int order, const Eigen::VectorXd& c) {
  return fpl::Polynomial(b.spanPowerMatrix(span) * c).derivativeAt(s, order) / std::pow(b.spanLength(span), order);
}

// Spans from 0.05 s to 1 s on [0, 3 s]: knots where a signal is fast, and a ratio of 20.
fpl::BSplineBasis graded(int degree) { return fpl::BSplineBasis(degree, {0.0, 0.05, 0.15, 0.4, 0.9, 2.0, 3.0}); }

double distance_to_a_knot(const fpl::BSplineBasis& b, double t) {
  double d = 1e9;
  for (double k : b.breakpoints()) d = std::min(d, std::abs(t - k));
  return d;
}
}  // namespace

TEST(BSplineBasis, NonnegativePartitionOfUnityWithClampedEnds) {
  for (int k : {1, 3, 5})
    for (int spans : {1, 4, 13, 0}) {
      const fpl::BSplineBasis b = spans ? fpl::BSplineBasis(k, spans, 2.5) : fpl::BSplineBasis(k, {0.0, 0.1, 0.3, 1.0, 2.5});
      ASSERT_EQ(b.size(), b.spans() + k);
      for (int i = 0; i <= 300; ++i) {
        const double t = 2.5 * i / 300.0;
        const Eigen::RowVectorXd v = b.derivativeRow(t, 0);
        EXPECT_NEAR(v.sum(), 1.0, 1e-12) << "k " << k << " spans " << spans << " t " << t;
        EXPECT_GE(v.minCoeff(), -1e-12);
        EXPECT_LE((v.array().abs() > 1e-14).count(), k + 1);  // local support
        EXPECT_NEAR(b.derivativeRow(t, 1).sum(), 0.0, 1e-9);
      }
      EXPECT_NEAR(b.derivativeRow(0.0, 0)[0], 1.0, 1e-12);
      EXPECT_NEAR(b.derivativeRow(2.5, 0)[b.size() - 1], 1.0, 1e-12);
    }
}

TEST(BSplineBasis, DerivativesAgreeWithFiniteDifferences) {
  for (const fpl::BSplineBasis& b : {fpl::BSplineBasis(5, 7, 3.0), graded(5)}) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.05, 2.95);
  Eigen::VectorXd c = Eigen::VectorXd::Random(b.size());
  const double e = 1e-4;
  for (int trial = 0; trial < 40; ++trial) {
    const double t = u(rng);
    if (distance_to_a_knot(b, t) < 3 * e) continue;  // the difference must stay on one span
    for (int order = 1; order <= 3; ++order) {
      const double fd = (-b.derivativeRow(t + 2 * e, order - 1).dot(c) + 8 * b.derivativeRow(t + e, order - 1).dot(c) -
                         8 * b.derivativeRow(t - e, order - 1).dot(c) + b.derivativeRow(t - 2 * e, order - 1).dot(c)) /
                        (12 * e);
      EXPECT_NEAR(b.derivativeRow(t, order).dot(c), fd, 1e-6 * (1 + std::abs(fd))) << "t " << t << " order " << order;
    }
  }
  }
}

TEST(BSplineBasis, ReproducesEveryPolynomialOfItsDegreeExactly) {
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int k : {3, 4, -3, -5}) {
    const fpl::BSplineBasis b = k > 0 ? fpl::BSplineBasis(k, 9, 3.0) : graded(-k);
    k = std::abs(k);
    Eigen::VectorXd pc(k + 1);
    for (auto& x : pc) x = n(rng);
    const fpl::Polynomial p(pc);
    // Least squares on many points (the basis holds p exactly, so the residual is rounding).
    const int samples = 40 * b.size();
    Eigen::MatrixXd A(samples, b.size());
    Eigen::VectorXd rhs(samples);
    for (int i = 0; i < samples; ++i) {
      const double t = 3.0 * i / (samples - 1);
      A.row(i) = b.derivativeRow(t, 0);
      rhs[i] = p(t);
    }
    const Eigen::VectorXd c = A.colPivHouseholderQr().solve(rhs);
    for (int i = 0; i <= 200; ++i) {
      const double t = 3.0 * i / 200.0;
      EXPECT_NEAR(b.derivativeRow(t, 0).dot(c), p(t), 1e-10) << "k " << k;
      EXPECT_NEAR(b.derivativeRow(t, 2).dot(c), p.derivativeAt(t, 2), 1e-8) << "k " << k;
    }
  }
}

TEST(BSplineBasis, ContinuousBelowItsDegreeAndNoMoreAtInteriorKnots) {
  for (const fpl::BSplineBasis& b : {fpl::BSplineBasis(3, 6, 3.0), graded(3)}) {
  const Eigen::VectorXd c = Eigen::VectorXd::Random(b.size());
  double jump_in_third = 0.0;
  for (int knot = 1; knot < b.spans(); ++knot) {
    for (int order = 0; order < 3; ++order)
      EXPECT_NEAR(span_derivative(b, knot - 1, 1.0, order, c), span_derivative(b, knot, 0.0, order, c), 1e-9)
          << "knot " << knot << " order " << order;
    jump_in_third = std::max(jump_in_third, std::abs(span_derivative(b, knot - 1, 1.0, 3, c) - span_derivative(b, knot, 0.0, 3, c)));
  }
  EXPECT_GT(jump_in_third, 1e-3);  // C2, not C3: the basis really has local freedom
  }
}

TEST(BSplineBasis, EvenlySpacedBreakpointsAreTheUniformBasis) {
  const fpl::BSplineBasis uniform(5, 6, 3.0), listed(5, {0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0});
  EXPECT_TRUE(uniform.uniform());
  EXPECT_FALSE(listed.uniform());
  for (int i = 0; i <= 300; ++i) {
    const double t = 3.0 * i / 300.0;
    EXPECT_EQ(uniform.spanAt(t), listed.spanAt(t)) << t;
    for (int order = 0; order <= 5; ++order)
      EXPECT_LT((uniform.derivativeRow(t, order) - listed.derivativeRow(t, order)).cwiseAbs().maxCoeff(),
                1e-9 * std::pow(2.0, order) * (1.0 + uniform.derivativeRow(t, order).cwiseAbs().maxCoeff()))
          << "t " << t << " order " << order;
  }
}

TEST(BSplineBasis, GeometricBreakpointsGrowByTheirRatioAndFillTheDuration) {
  for (double growth : {0.8, 1.0, 1.06, 1.4})
    for (int spans : {1, 2, 12, 48}) {
      const std::vector<double> b = fpl::geometric_breakpoints(spans, 3.0, growth);
      ASSERT_EQ(b.size(), static_cast<std::size_t>(spans + 1));
      EXPECT_EQ(b.front(), 0.0);
      EXPECT_EQ(b.back(), 3.0);
      for (int i = 1; i + 1 <= spans; ++i) {
        EXPECT_GT(b[i], b[i - 1]);
        if (i >= 2) {
          EXPECT_NEAR((b[i] - b[i - 1]) / (b[i - 1] - b[i - 2]), growth, 1e-9) << growth << " " << spans << " " << i;
        }
      }
      if (spans >= 2) {
        EXPECT_NEAR((b[spans] - b[spans - 1]) / (b[spans - 1] - b[spans - 2]), growth, 1e-9);
      }
      // Growth 1 is the uniform basis' own arithmetic, bit for bit.
      if (growth == 1.0) {
        for (int i = 0; i <= spans; ++i) EXPECT_EQ(b[static_cast<std::size_t>(i)], 3.0 * i / spans);
      }
      const fpl::BSplineBasis basis = fpl::BSplineBasis::geometric(3, spans, 3.0, growth);
      EXPECT_EQ(basis.uniform(), growth == 1.0);
      for (int i = 0; i < spans; ++i) EXPECT_NEAR(basis.spanStart(i), b[static_cast<std::size_t>(i)], 1e-12);
    }
  EXPECT_THROW(fpl::geometric_breakpoints(0, 3.0, 1.1), std::invalid_argument);
  EXPECT_THROW(fpl::geometric_breakpoints(4, 0.0, 1.1), std::invalid_argument);
  EXPECT_THROW(fpl::geometric_breakpoints(4, 3.0, 0.0), std::invalid_argument);
  EXPECT_THROW(fpl::geometric_breakpoints(4, 3.0, std::nan("")), std::invalid_argument);
}

TEST(BSplineBasis, RejectsBadInput) {
  EXPECT_THROW(fpl::BSplineBasis(0, 3, 1.0), std::invalid_argument);
  EXPECT_THROW(fpl::BSplineBasis(3, 0, 1.0), std::invalid_argument);
  EXPECT_THROW(fpl::BSplineBasis(3, 3, 0.0), std::invalid_argument);
  EXPECT_THROW(fpl::BSplineBasis(3, 3, std::nan("")), std::invalid_argument);
  EXPECT_THROW(fpl::BSplineBasis(3, std::vector<double>{0.0}), std::invalid_argument);
  EXPECT_THROW(fpl::BSplineBasis(3, {0.1, 1.0}), std::invalid_argument);
  EXPECT_THROW(fpl::BSplineBasis(3, {0.0, 1.0, 1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(fpl::BSplineBasis(3, {0.0, 1.0, std::nan("")}), std::invalid_argument);
  EXPECT_THROW(fpl::BSplineBasis(0, {0.0, 1.0}), std::invalid_argument);
}

TEST(SplineTrajectory, JetAgreesWithTheBasisRowsEverywhere) {
  // Two evaluation routes: per-span power coefficients by Horner (the trajectory) and the basis
  // functions' derivative rows (Cox-de Boor) times the coefficients.
  for (const fpl::BSplineBasis& basis : {fpl::BSplineBasis(3, 7, 2.5), fpl::BSplineBasis(3, {0.0, 0.1, 0.3, 0.7, 1.4, 2.5})}) {
  Eigen::MatrixXd c = Eigen::MatrixXd::Random(3, basis.size()) * 100.0;
  const fpl::SplineTrajectory y(basis, c);
  // The shortest span sets the derivatives' scale (1/h per order).
  double shortest_s = 2.5;
  for (int span = 0; span < basis.spans(); ++span) shortest_s = std::min(shortest_s, basis.spanLength(span));
  std::vector<double> times = basis.breakpoints();  // ends and every knot
  for (int i = 0; i <= 700; ++i) times.push_back(2.5 * i / 700.0);
  for (double t : times) {
    const Eigen::MatrixXd jet = y.jet(t, 4);
    for (int k = 0; k < 4; ++k) {
      const Eigen::VectorXd expected = c * basis.derivativeRow(t, k).transpose();
      for (int r = 0; r < 3; ++r)
        EXPECT_NEAR(jet(r, k), expected[r], 1e-9 * (1.0 + std::abs(expected[r])) * std::pow(1.0 / shortest_s, k)) << t << " " << k;
      EXPECT_NEAR(y.derivativeAt(1, t, k), expected[1], 1e-9 * (1.0 + std::abs(expected[1])) * std::pow(1.0 / shortest_s, k));
    }
  }
  }
  const fpl::BSplineBasis basis(3, 7, 2.5);
  const Eigen::MatrixXd c = Eigen::MatrixXd::Random(3, basis.size());
  EXPECT_THROW(fpl::SplineTrajectory(basis, Eigen::MatrixXd::Zero(3, basis.size() + 1)), std::invalid_argument);
  Eigen::MatrixXd bad = c;
  bad(0, 0) = std::nan("");
  EXPECT_THROW(fpl::SplineTrajectory(basis, bad), std::invalid_argument);
}

// A spline of a coarse geometric basis is a spline of the finer one whose breakpoints include
// its own (every f-th breakpoint of S spans growing by g are those of S/f spans growing by g^f):
// the same values and derivatives everywhere. A basis without its breakpoints, or a lower degree,
// cannot hold it and is refused.
TEST(SplineTrajectory, InAFinerBasisHoldingItsBreakpointsTheSignalsAreUnchanged) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coefficient(-200.0, 200.0);
  for (const auto& [degree, spans, growth, factor] :
       std::vector<std::tuple<int, int, double, int>>{{5, 48, 1.06, 2}, {5, 48, 1.06, 4}, {3, 24, 1.0, 3}, {4, 12, 0.9, 2}}) {
    const fpl::BSplineBasis fine = fpl::BSplineBasis::geometric(degree, spans, 3.0, growth);
    const fpl::BSplineBasis coarse = fpl::BSplineBasis::geometric(degree, spans / factor, 3.0, std::pow(growth, factor));
    for (int k = 0; k < coarse.spans(); ++k) ASSERT_NEAR(coarse.breakpoints()[k], fine.breakpoints()[k * factor], 1e-13);
    Eigen::MatrixXd c(2, coarse.size());
    for (Eigen::Index i = 0; i < c.size(); ++i) c(i) = coefficient(rng);
    const fpl::SplineTrajectory y(coarse, c);
    const fpl::SplineTrajectory refined = y.inBasis(fine);
    EXPECT_EQ(refined.basis().spans(), spans);
    double shortest_s = 3.0;
    for (int span = 0; span < fine.spans(); ++span) shortest_s = std::min(shortest_s, fine.spanLength(span));
    for (int i = 0; i <= 900; ++i) {
      const double t = 3.0 * i / 900.0;
      const Eigen::MatrixXd a = y.jet(t, degree), b = refined.jet(t, degree);
      for (int order = 0; order < degree; ++order)
        for (int r = 0; r < 2; ++r)
          EXPECT_NEAR(b(r, order), a(r, order), 1e-9 * 200.0 * std::pow(1.0 / shortest_s, order)) << t << " order " << order;
    }
  }
  // Breakpoints of the coarse basis missing from the other: not its splines.
  const fpl::BSplineBasis coarse(3, 4, 3.0), other(3, 5, 3.0);
  const fpl::SplineTrajectory y(coarse, Eigen::MatrixXd::Random(1, coarse.size()) * 100.0);
  EXPECT_THROW(y.inBasis(other), std::invalid_argument);
  EXPECT_THROW(y.inBasis(fpl::BSplineBasis(2, 8, 3.0)), std::invalid_argument);  // a lower degree
  EXPECT_THROW(y.inBasis(fpl::BSplineBasis(3, 8, 2.0)), std::invalid_argument);  // another duration
  // Itself: the same coefficients.
  EXPECT_LT((y.inBasis(coarse).coefficients() - y.coefficients()).cwiseAbs().maxCoeff(), 1e-10);
}

TEST(SplineTrajectory, BeyondItsEndsTheContinuedJetFollowsTheEndSpansPolynomials) {
  // Inside [0, T] the continued jet is the jet; beyond, the first or last span's polynomial
  // continued, so its Taylor series from the end's jet (exact: degree 5, six orders).
  const fpl::BSplineBasis basis = graded(5);
  const Eigen::MatrixXd c = Eigen::MatrixXd::Random(2, basis.size());
  const fpl::SplineTrajectory y(basis, c);
  Eigen::MatrixXd inside(2, 6), continued(2, 6);
  for (double t : {0.0, 0.01, 0.7, 3.0}) {
    y.jetInto(t, inside);
    y.continuedJetInto(t, continued);
    EXPECT_EQ((inside - continued).cwiseAbs().maxCoeff(), 0.0) << t;
  }
  for (const auto& [end, dt] : {std::pair{0.0, -0.02}, std::pair{3.0, 0.3}}) {
    const Eigen::MatrixXd at_end = y.jet(end, 6);
    y.continuedJetInto(end + dt, continued);
    for (int k = 0; k < 6; ++k) {
      Eigen::VectorXd taylor = Eigen::VectorXd::Zero(2);
      double term = 1.0;
      for (int j = k; j < 6; ++j, term *= dt / (j - k)) taylor += term * at_end.col(j);
      EXPECT_LT((continued.col(k) - taylor).cwiseAbs().maxCoeff(), 1e-7 * (1.0 + taylor.cwiseAbs().maxCoeff()))
          << "t = " << end + dt << ", order " << k;
    }
    // Not frozen at the end value (what jet, clamped, gives).
    EXPECT_GT((continued.col(0) - at_end.col(0)).cwiseAbs().maxCoeff(), 1e-6);
  }
}

TEST(BSplineBasis, PointsPerSpanStartEachSpanAndDivideItEvenly) {
  const fpl::BSplineBasis basis = fpl::BSplineBasis::geometric(3, 4, 3.0, 1.5);
  const std::vector<double> times = basis.pointsPerSpan(2);
  ASSERT_EQ(times.size(), 8u);
  for (int span = 0; span < 4; ++span) {
    EXPECT_EQ(times[static_cast<std::size_t>(2 * span)], basis.spanStart(span));
    EXPECT_NEAR(times[static_cast<std::size_t>(2 * span + 1)], basis.spanStart(span) + 0.5 * basis.spanLength(span), 1e-15);
  }
  EXPECT_TRUE(basis.pointsPerSpan(0).empty());
}
