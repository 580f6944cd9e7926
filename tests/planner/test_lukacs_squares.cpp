// Markov-Lukacs with single squares (numerics/lukacs_squares.hpp): p = f^2 + s(1-s) g^2 built
// from p's roots, checked against p's coefficients on random polynomials >= 0 on [0, 1] of every
// degree up to 10 (odd ones in the next even family), with zeros inside, at the ends and near.
#include <gtest/gtest.h>

#include <complex>
#include <random>

#include "numerics/lukacs_squares.hpp"

namespace fpl = flatsos::planner;
namespace fd = flatsos::planner::detail;

namespace {

fpl::Polynomial linear(double c0, double c1) { return fpl::Polynomial(Eigen::Vector2d(c0, c1)); }

// A random product of factors >= 0 on [0, 1]: complex pairs, real roots outside (in pairs on
// one side or singly with the sign that keeps the product positive there), double roots inside.
fpl::Polynomial random_nonnegative(std::mt19937& rng, int degree, bool zeros_inside) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  fpl::Polynomial p(Eigen::VectorXd::Constant(1, 0.5 + u(rng)));
  int d = 0;
  while (d < degree) {
    const double kind = u(rng);
    if (degree - d >= 2 && zeros_inside && kind < 0.3) {
      const double r = u(rng);  // a double zero in [0, 1]
      p = p * linear(-r, 1.0) * linear(-r, 1.0);
      d += 2;
    } else if (degree - d >= 2 && kind < 0.65) {
      const std::complex<double> z(-0.5 + 2.0 * u(rng), 0.05 + u(rng));
      p = p * fpl::Polynomial(Eigen::Vector3d(std::norm(z), -2.0 * z.real(), 1.0));
      d += 2;
    } else {
      // s - r with r < 0, or r - s with r > 1.
      p = u(rng) < 0.5 ? p * linear(0.01 + 2.0 * u(rng), 1.0) : p * linear(1.01 + 2.0 * u(rng), -1.0);
      d += 1;
    }
  }
  return p;
}

double relative_residual(const fpl::Polynomial& p, const fd::LukacsSquares& sq) {
  const Eigen::VectorXd q = fd::lukacs_squares_polynomial(sq);
  Eigen::VectorXd c = Eigen::VectorXd::Zero(q.size());
  c.head(p.coefficients().size()) = p.coefficients();
  return (q - c).cwiseAbs().maxCoeff() / c.cwiseAbs().maxCoeff();
}

}  // namespace

TEST(LukacsSquares, RepresentsPositivePolynomialsOfEveryDegree) {
  std::mt19937 rng(3);
  for (int degree = 0; degree <= 10; ++degree)
    for (int trial = 0; trial < 40; ++trial) {
      const fpl::Polynomial p = random_nonnegative(rng, degree, false);
      const int half = (degree + 1) / 2;
      const fd::LukacsSquares sq = fd::lukacs_squares(p, half);
      ASSERT_EQ(sq.f.size(), half + 1);
      ASSERT_EQ(sq.g.size(), half);
      // The roots' rounding (companion-matrix eigenvalues in the monomial basis) grows with the
      // degree: measured worst 2e-12 up to 6, 2e-11 at 7-8, 4e-10 at 9-10 (a start for Newton, which refines it).
      const double allowed = degree <= 6 ? 1e-11 : degree <= 8 ? 1e-10 : 2e-9;
      EXPECT_LT(relative_residual(p, sq), allowed) << "degree " << degree << " trial " << trial;
    }
}

TEST(LukacsSquares, RepresentsPolynomialsWithDoubleZerosInside) {
  // The zeros come out of the eigenvalues split by about sqrt(eps): paired again, the product
  // matches to that rounding.
  std::mt19937 rng(5);
  for (int degree : {2, 4, 6, 8})
    for (int trial = 0; trial < 40; ++trial) {
      const fpl::Polynomial p = random_nonnegative(rng, degree, true);
      const fd::LukacsSquares sq = fd::lukacs_squares(p, degree / 2);
      EXPECT_LT(relative_residual(p, sq), 1e-7) << "degree " << degree << " trial " << trial;
    }
}

TEST(LukacsSquares, HandlesZerosAtTheEndsAndLowerDegreesInALargerFamily) {
  // s^2 (a double zero at the end), s (1 - s) (simple zeros at both ends), s and 1 - s.
  for (const Eigen::VectorXd& c : {Eigen::VectorXd(Eigen::Vector3d(0, 0, 1)), Eigen::VectorXd(Eigen::Vector3d(0, 1, -1)),
                                   Eigen::VectorXd(Eigen::Vector2d(0, 1)), Eigen::VectorXd(Eigen::Vector2d(1, -1))}) {
    const fpl::Polynomial p(c);
    for (int half : {1, 2, 3}) EXPECT_LT(relative_residual(p, fd::lukacs_squares(p, half)), 1e-14) << c.transpose();
  }
  // A constant and zero.
  EXPECT_LT(relative_residual(fpl::Polynomial(Eigen::VectorXd::Constant(1, 4.0)), fd::lukacs_squares(fpl::Polynomial(Eigen::VectorXd::Constant(1, 4.0)), 2)), 1e-15);
  const fd::LukacsSquares zero = fd::lukacs_squares(fpl::Polynomial(Eigen::VectorXd::Zero(3)), 1);
  EXPECT_EQ(zero.f.norm() + zero.g.norm(), 0.0);
}

TEST(LukacsSquares, RejectsADegreeAboveTheFamily) {
  const fpl::Polynomial p(Eigen::VectorXd::Ones(6));  // degree 5
  EXPECT_THROW(fd::lukacs_squares(p, 2), std::invalid_argument);
  EXPECT_NO_THROW(fd::lukacs_squares(p, 3));
}
