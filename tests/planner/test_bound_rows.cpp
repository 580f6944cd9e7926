// The bounds' rows of one muscle: compressed where |r| > 1 (same sign, so the same feasible set;
// C1; slopes matching finite differences), finite for a fibre stretched so far that its
// activation is astronomically large, and outside the muscle's domain more violated than any
// row inside with the domain distance's gradient, so that an optimizer is led back in.
#include <gtest/gtest.h>

#include "example_muscles.hpp"
#include "finite_difference.hpp"

#include <cmath>

#include "bounds/bound_rows.hpp"
#include "flatsos/muscles/muscle_inverse.hpp"

namespace fpd = flatsos::planner::detail;
namespace fm = flatsos::muscles;
using flatsos::test::central_difference;

namespace {

fm::MuscleParameters triceps() { return flatsos::test::example_triceps(); }

}  // namespace

TEST(BoundRows, CompressionKeepsTheSignAndIsTheIdentityInsideTheUnitInterval) {
  for (double r : {-1.0, -0.3, 0.0, 1e-9, 0.7, 1.0}) {
    EXPECT_EQ(fpd::compress_row(r).value, r);
    EXPECT_EQ(fpd::compress_row(r).slope, 1.0);
  }
  double previous = -1e300;
  for (double r : {-1e300, -1e86, -1e3, -2.0, -1.0 - 1e-12, 1.0 + 1e-12, 2.0, 1e3, 1e86, 1e300}) {
    const fpd::CompressedRow c = fpd::compress_row(r);
    EXPECT_EQ(std::signbit(c.value), std::signbit(r)) << r;
    EXPECT_GT(c.value, previous) << "monotone at " << r;
    EXPECT_LT(std::abs(c.value), 1.0 + std::log(1e300) + 1e-9) << r;
    previous = c.value;
    const double h = 1e-6 * std::abs(r);
    EXPECT_MATCHES_FINITE_DIFFERENCE(c.slope, central_difference([](double x) { return fpd::compress_row(x).value; }, r, h))
        << r;
  }
  // C1 at |r| = 1: value and slope continuous.
  EXPECT_NEAR(fpd::compress_row(1.0 + 1e-12).value, 1.0, 1e-11);
  EXPECT_NEAR(fpd::compress_row(1.0 + 1e-12).slope, 1.0, 1e-11);
  EXPECT_NEAR(fpd::compress_row(-1.0 - 1e-12).value, -1.0, 1e-11);
}

TEST(BoundRows, AFarStretchedFibreGivesFiniteRowsWithMatchingGradients) {
  const fm::MuscleParameters p = triceps();
  // A fibre at 3.2 optimal lengths: f = exp(-((3.2 - 1) / 0.56)^2)... about 2e-7; 400 N
  // then needs an activation of thousands.
  const fm::SecondOrderJet force{400.0, 50.0, 10.0};
  const double ls = fm::tendon_length_from_force(p, force.value);
  const fm::SecondOrderJet path{ls + 3.2 * p.optimal_fiber_length_m, 0.01, 0.0};
  const fm::MuscleInverse inv = fm::invert_muscle(p, force, path, false);
  ASSERT_EQ(inv.stage, fm::MuscleInverse::Stage::Complete);
  ASSERT_GT(inv.activation, 1e3);
  const fpd::MuscleBoundRows rows = fpd::muscle_bound_rows(p, force, path, 0.01, true);
  ASSERT_TRUE(rows.in_domain);
  EXPECT_LT(rows.value[1], -1.0);  // a <= 1 violated ...
  EXPECT_GT(rows.value[1], -30.0);  // ... by a compressed amount
  for (std::size_t k = 0; k < rows.value.size(); ++k) {
    EXPECT_TRUE(std::isfinite(rows.value[k]));
    auto row_at = [&](double F) {
      fm::SecondOrderJet f = force;
      f.value = F;
      return fpd::muscle_bound_rows(p, f, path, 0.01, false).value[k];
    };
    EXPECT_MATCHES_FINITE_DIFFERENCE(rows.gradient[k][0], central_difference(row_at, force.value, 1e-4 * force.value))
        << "row " << k;
  }
}

TEST(BoundRows, OutsideTheDomainEveryRowIsMoreViolatedThanAnyRowInside) {
  const fm::MuscleParameters p = triceps();
  const fm::SecondOrderJet path{p.tendon_slack_length_m + p.optimal_fiber_length_m, 0.0, 0.0};
  const fm::SecondOrderJet slack{-40.0, 0.0, 0.0};
  const fpd::MuscleBoundRows rows = fpd::muscle_bound_rows(p, slack, path, 0.01, true);
  EXPECT_FALSE(rows.in_domain);
  for (std::size_t k = 0; k < rows.value.size(); ++k) {
    // Any compressed row inside is above -(1 + ln DBL_MAX) > -711.
    EXPECT_LT(rows.value[k], -fpd::kOutsideDomain);
    // Less violated toward the domain (F up): d row / dF = 1 / Fmax.
    EXPECT_DOUBLE_EQ(rows.gradient[k][0], 1.0 / p.max_isometric_force_N);
    auto row_at = [&](double F) { return fpd::muscle_bound_rows(p, {F, 0.0, 0.0}, path, 0.01, false).value[k]; };
    EXPECT_MATCHES_FINITE_DIFFERENCE(rows.gradient[k][0], central_difference(row_at, slack.value, 1.0));
  }
}
