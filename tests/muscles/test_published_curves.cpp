// Thelen's (2003, as OpenSim 4 implements it) and De Groote et al.'s (2016, with OpenSim's
// corrections) curves against their published equations, written out again here, at 1000
// points each (1e-9 relative), and the inverses by round trip.
//   Thelen: fL = exp(-(l - 1)^2 / 0.45); fPE = (exp(kPE (l - 1) / e0) - 1) / (exp(kPE) - 1) beyond
//   l = 1 (0 below), kPE = 5, e0 = 0.6; tendon toe Ftoe (exp(kToe e / eToe) - 1) / (exp(kToe) - 1)
//   up to eToe = 99 e0T e^3 / (166 e^3 - 67), then Ftoe + klin (e - eToe), klin = 0.67 / (e0T - eToe),
//   Ftoe = 0.33, kToe = 3, e0T = 0.04; shortening velocity u / Vmax = (1 - z) / (1 + z / Af) for
//   z <= 1, -(z - 1) (Flen - 1) / ((2 + 2 / Af)(Flen - z)) above, Af = 0.25, Flen = 1.4.
//   De Groote: fT = c1 exp(kT e) - c3 (c1 = c3 = 0.2, kT = ln((1 + c3) / c1) / e0T, e0T = 0.049);
//   fL = sum of three b1 exp(-(l - b2)^2 / (2 (b3 + b4 l)^2)); fPE = (exp(kPE (l - 1) / e0) - o) /
//   (exp(kPE) - o), o = exp(kPE (0.2 - 1) / e0), kPE = 4, e0 = 0.6; fV = d1 ln(s + sqrt(s^2 + 1)) +
//   d4, s = d2 v + d3, v the lengthening velocity over Vmax.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/muscles/muscle_model.hpp"
#include "example_muscles.hpp"

namespace fm = flatsos::muscles;

namespace {

fm::MuscleParameters muscle(const std::string& model) { return flatsos::test::muscle_with_defaults(model); }

// The largest |ours - published| / max(|published|, floor) over 1000 points of [lo, hi].
double worst_relative(double lo, double hi, const std::function<double(double)>& ours,
                      const std::function<double(double)>& published, double floor = 1e-12) {
  double worst = 0.0;
  for (int i = 0; i < 1000; ++i) {
    const double x = lo + (hi - lo) * (i + 0.5) / 1000.0;
    const double expected = published(x);
    worst = std::max(worst, std::abs(ours(x) - expected) / std::max(std::abs(expected), floor));
  }
  return worst;
}

TEST(PublishedCurves, ThelensCurvesAreThelens) {
  const fm::MuscleParameters p = muscle("thelen2003");
  const double lopt = p.optimal_fiber_length_m, slack = p.tendon_slack_length_m, fmax = p.max_isometric_force_N;
  EXPECT_LT(worst_relative(0.3, 1.8, [&](double l) { return fm::force_length(p, l * lopt); },
                           [](double l) { return std::exp(-(l - 1.0) * (l - 1.0) / 0.45); }),
            1e-9);
  EXPECT_LT(worst_relative(1.0, 1.7, [&](double l) { return fm::passive_fiber_force(p, l * lopt) / fmax; },
                           [](double l) { return std::expm1(5.0 * (l - 1.0) / 0.6) / std::expm1(5.0); }),
            1e-9);
  EXPECT_EQ(fm::passive_fiber_force(p, 0.9 * lopt), 0.0);
  const double e0 = 0.04, e3 = std::exp(3.0), toe = 99.0 * e0 * e3 / (166.0 * e3 - 67.0);
  const auto tendon = [&](double e) {
    return e <= toe ? 0.33 * std::expm1(3.0 * e / toe) / std::expm1(3.0) : 0.33 + 0.67 / (e0 - toe) * (e - toe);
  };
  EXPECT_LT(worst_relative(1e-4, 0.06, [&](double e) { return fm::tendon_force(p, slack * (1.0 + e)) / fmax; }, tendon),
            1e-9);
  const double vmax = p.max_shortening_velocity_m_per_s(), af = 0.25, flen = 1.4;
  const auto shortening = [&](double z) {
    return vmax * (z <= 1.0 ? (1.0 - z) / (1.0 + z / af) : -(z - 1.0) * (flen - 1.0) / ((2.0 + 2.0 / af) * (flen - z)));
  };
  // g at the published velocity returns the force ratio (the exact branches, below 0.95 Flen).
  EXPECT_LT(worst_relative(0.0, 0.95 * flen, [&](double z) { return fm::force_velocity(p, shortening(z)); },
                           [](double z) { return z; }, 1e-3),
            1e-9);
  for (const double z : {0.0, 0.3, 1.0, 1.2, 1.3})
    EXPECT_NEAR(fm::force_velocity_inverse(p, z), shortening(z), 1e-9 * vmax) << z;
}

TEST(PublishedCurves, DeGrooteFreglysCurvesAreDeGrootes) {
  const fm::MuscleParameters p = muscle("degroote_fregly2016");
  const double lopt = p.optimal_fiber_length_m, slack = p.tendon_slack_length_m, fmax = p.max_isometric_force_N;
  const double kt = std::log(1.2 / 0.2) / 0.049;
  EXPECT_LT(worst_relative(-0.01, 0.06, [&](double e) { return fm::tendon_force(p, slack * (1.0 + e)) / fmax; },
                           [&](double e) { return 0.2 * std::exp(kt * e) - 0.2; }, 1e-3),
            1e-9);
  // The paper's constants to the digits OpenSim carries (b11 such that fL(1) = 1).
  const double b[3][4] = {{0.8150671134243542, 1.055033428970575, 0.162384573599574, 0.063303448465465},
                          {0.433004984392647, 0.716775413397760, -0.029947116970696, 0.200356847296188},
                          {0.1, 1.0, 0.5 * std::sqrt(0.5), 0.0}};
  const auto active = [&](double l) {
    double sum = 0.0;
    for (const auto& c : b) {
      const double w = c[2] + c[3] * l;
      sum += c[0] * std::exp(-0.5 * (l - c[1]) * (l - c[1]) / (w * w));
    }
    return sum;
  };
  EXPECT_LT(worst_relative(0.4, 1.8, [&](double l) { return fm::force_length(p, l * lopt); }, active), 1e-9);
  EXPECT_NEAR(fm::force_length(p, lopt), 1.0, 1e-12);
  const double offset = std::exp(4.0 * (0.2 - 1.0) / 0.6);
  EXPECT_LT(worst_relative(0.3, 1.8, [&](double l) { return fm::passive_fiber_force(p, l * lopt) / fmax; },
                           [&](double l) { return (std::exp(4.0 * (l - 1.0) / 0.6) - offset) / (std::exp(4.0) - offset); }),
            1e-9);
  // d1 and d4 are OpenSim's: g(-1) = 0 and g(0) = 1 exactly.
  const double d2 = -8.149, d3 = -0.374;
  const double d1 = 1.0 / (std::asinh(d3) - std::asinh(d3 - d2)), d4 = 1.0 - d1 * std::asinh(d3);
  const double vmax = p.max_shortening_velocity_m_per_s();
  const auto g = [&](double v) { const double s = d2 * v + d3; return d1 * std::log(s + std::sqrt(s * s + 1.0)) + d4; };
  EXPECT_LT(worst_relative(-1.0, 1.0, [&](double v) { return fm::force_velocity(p, -v * vmax); }, g, 1e-3), 1e-9);
  for (const double z : {0.05, 0.5, 1.0, 1.5, 1.75})
    EXPECT_NEAR(fm::force_velocity(p, fm::force_velocity_inverse(p, z)), z, 1e-12) << z;
}

}  // namespace
