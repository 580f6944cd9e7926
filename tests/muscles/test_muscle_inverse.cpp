// The inverse of one muscle: second derivatives of the force-length and force-velocity laws
// against finite differences; the inverse's gradients (activation and excitation with respect to
// the tendon-force jet and to the path-length jet) against finite differences; the forward laws
// reproduce what the inverse says (round trip); and the stages where nothing further is defined.
#include <gtest/gtest.h>

#include "example_muscles.hpp"
#include "finite_difference.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <tuple>

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/muscles/muscle_inverse.hpp"

namespace fm = flatsos::muscles;
using flatsos::test::central_difference;
using flatsos::test::default_step;

namespace {

fm::MuscleParameters triceps() { return flatsos::test::example_triceps(); }

// The same muscle with pennation (0.35 rad) and passive fibre force (e0 = 0.6); with fibre
// damping; as Thelen's muscle, whose maximum velocity scales with activation, alone and
// pennated, passive and damped; and as OpenSim's default Millard muscle, alone and pennated.
std::vector<fm::MuscleParameters> variants() {
  fm::MuscleParameters pennated = triceps();
  pennated.name = "triceps, pennated with passive force";
  pennated.pennation_angle_at_optimal_rad = 0.35;
  pennated.passive_fiber_strain_at_one_norm_force = 0.6;
  fm::MuscleParameters damped = triceps();
  damped.name = "triceps, damped";
  damped.fiber_damping = 0.1;
  fm::MuscleParameters thelen = triceps();
  thelen.name = "triceps, Thelen 2003";
  thelen.model = fm::muscle_model_named("thelen2003");
  thelen.model->setDefaults(thelen);
  fm::MuscleParameters thelen_all = thelen;
  thelen_all.name = "triceps, Thelen 2003, pennated, passive and damped";
  thelen_all.pennation_angle_at_optimal_rad = 0.35;
  thelen_all.fiber_damping = 0.05;
  // OpenSim's default Millard muscle: Bezier curves, damped, a fibre-length floor; and pennated.
  fm::MuscleParameters millard = triceps();
  millard.name = "triceps, Millard 2012";
  millard.model = fm::muscle_model_named("millard2012");
  millard.model->setDefaults(millard);
  fm::MuscleParameters millard_pennated = millard;
  millard_pennated.name = "triceps, Millard 2012, pennated";
  millard_pennated.pennation_angle_at_optimal_rad = 0.35;
  return {triceps(), pennated, damped, thelen, thelen_all, millard, millard_pennated};
}

struct Sample {
  fm::SecondOrderJet force, path;
};

// States with activations in (max(0.005, floor), 1) and real excitations, spread over the fibre's range.
std::vector<Sample> samples(const fm::MuscleParameters& p, int count) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Sample> out;
  while (static_cast<int>(out.size()) < count) {
    Sample s;
    s.force = {5.0 + 600.0 * unit(rng), -800.0 + 1600.0 * unit(rng), -2e4 + 4e4 * unit(rng)};
    const double ls = fm::tendon_length_from_force(p, s.force.value);
    s.path = {ls + p.optimal_fiber_length_m * (0.6 + 0.8 * unit(rng)), -0.3 + 0.6 * unit(rng), -3.0 + 6.0 * unit(rng)};
    const fm::MuscleInverse inv = fm::invert_muscle(p, s.force, s.path, false);
    // Where the forward model is the inverse's exact twin: above the activation floor, and g
    // where the forward model uses its exact inverse.
    if (inv.stage == fm::MuscleInverse::Stage::Complete && inv.excitation_real &&
        inv.activation > std::max(0.005, p.activation_floor) && inv.activation < 1.0 &&
        inv.force_ratio <= fm::force_ratio_exact_upper_bound(p) && std::abs(inv.shortening_velocity_m_per_s) > 1e-3)
      out.push_back(s);
  }
  return out;
}

}  // namespace

TEST(MuscleLawSecondDerivatives, MatchFiniteDifferences) {
  const auto p = triceps();
  for (int i = 0; i <= 40; ++i) {
    const double lc = p.optimal_fiber_length_m * (0.3 + 1.5 * i / 40.0);
    EXPECT_MATCHES_FINITE_DIFFERENCE(
        fm::force_length_second_derivative(p, lc),
        central_difference([&](double x) { return fm::force_length_derivative(p, x); }, lc, default_step(lc, p.optimal_fiber_length_m)));
  }
  const double vmax = p.max_shortening_velocity_m_per_s();
  for (int i = 0; i <= 40; ++i) {
    const double u = vmax * (-3.0 + 3.95 * i / 40.0);
    if (std::abs(u) < 0.02 * vmax) continue;  // g'' jumps at u = 0 (g is C1 there)
    EXPECT_MATCHES_FINITE_DIFFERENCE(
        fm::force_velocity_second_derivative(p, u),
        central_difference([&](double x) { return fm::force_velocity_derivative(p, x); }, u, default_step(0.0, 1e-3 * vmax)))
        << u;
  }
}

TEST(MuscleInverse, GradientsMatchFiniteDifferences) {
  for (const auto& p : variants()) {
    SCOPED_TRACE(p.name);
    for (const Sample& s : samples(p, 60)) {
      const fm::MuscleInverse inv = fm::invert_muscle(p, s.force, s.path, true);
      const double scales[3] = {1.0, 10.0, 100.0};
      for (int k = 0; k < 3; ++k) {
        auto vary = [&](double x, int which) {
          fm::SecondOrderJet f = s.force;
          (k == 0 ? f.value : k == 1 ? f.rate : f.acceleration) = x;
          const fm::MuscleInverse v = fm::invert_muscle(p, f, s.path, false);
          return which == 0 ? v.activation : which == 1 ? v.activation_rate_per_s : v.excitation;
        };
        const double x0 = k == 0 ? s.force.value : k == 1 ? s.force.rate : s.force.acceleration;
        const double h = default_step(x0, scales[k]);
        EXPECT_MATCHES_FINITE_DIFFERENCE(inv.activation_gradient[k], central_difference([&](double x) { return vary(x, 0); }, x0, h))
            << "d a / d x" << k;
        EXPECT_MATCHES_FINITE_DIFFERENCE(inv.activation_rate_gradient[k], central_difference([&](double x) { return vary(x, 1); }, x0, h))
            << "d da/dt / d x" << k;
        EXPECT_MATCHES_FINITE_DIFFERENCE(inv.excitation_gradient[k], central_difference([&](double x) { return vary(x, 2); }, x0, h))
            << "d n / d x" << k;
      }
    }
  }
}

TEST(MuscleInverse, PathGradientsMatchFiniteDifferences) {
  for (const auto& p : variants()) {
    SCOPED_TRACE(p.name);
    int checked = 0;
    for (const Sample& s : samples(p, 60)) {
      const fm::MuscleInverse inv = fm::invert_muscle(p, s.force, s.path, true);
      if (inv.stage != fm::MuscleInverse::Stage::Complete) continue;
      const double scales[3] = {p.optimal_fiber_length_m, 0.1, 1.0};  // m, m/s, m/s^2
      for (int k = 0; k < 3; ++k) {
        auto vary = [&](double x, int which) {
          fm::SecondOrderJet path = s.path;
          (k == 0 ? path.value : k == 1 ? path.rate : path.acceleration) = x;
          const fm::MuscleInverse v = fm::invert_muscle(p, s.force, path, false);
          return which == 0 ? v.activation : which == 1 ? v.activation_rate_per_s : v.excitation;
        };
        const double x0 = k == 0 ? s.path.value : k == 1 ? s.path.rate : s.path.acceleration;
        const double h = default_step(x0, 1e-3 * scales[k]);
        EXPECT_MATCHES_FINITE_DIFFERENCE(inv.path_activation_gradient[k], central_difference([&](double x) { return vary(x, 0); }, x0, h))
            << "d a / d L" << k;
        EXPECT_MATCHES_FINITE_DIFFERENCE(inv.path_activation_rate_gradient[k],
                                         central_difference([&](double x) { return vary(x, 1); }, x0, h))
            << "d da/dt / d L" << k;
        if (inv.excitation_real) {
          EXPECT_MATCHES_FINITE_DIFFERENCE(inv.path_excitation_gradient[k],
                                           central_difference([&](double x) { return vary(x, 2); }, x0, h))
              << "d n / d L" << k;
        }
      }
      // The length moves a and da/dt (through f and g): the gradients are not trivially zero.
      EXPECT_NE(inv.path_activation_gradient[0], 0.0);
      EXPECT_NE(inv.path_activation_rate_gradient[2], 0.0);
      ++checked;
    }
    EXPECT_GE(checked, 30);
  }
}

TEST(MuscleInverse, ForwardLawsReproduceTheInverse) {
  for (const auto& p : variants()) {
    SCOPED_TRACE(p.name);
    for (const Sample& s : samples(p, 60)) {
      const fm::MuscleInverse inv = fm::invert_muscle(p, s.force, s.path, false);
      EXPECT_NEAR(fm::tendon_force(p, inv.tendon_length_m), s.force.value, 1e-10 * s.force.value);
      // The contraction dynamics with this activation give the tendon's planned rate ...
      const double dls = fm::tendon_length_derivative(p, inv.tendon_length_m, inv.activation, s.path.value, s.path.rate);
      EXPECT_NEAR(dls, inv.tendon_length_rate_m_per_s, 1e-9 * (1.0 + std::abs(dls)));
      EXPECT_NEAR(fm::tendon_force_derivative(p, inv.tendon_length_m) * dls, s.force.rate, 1e-7 * (1.0 + std::abs(s.force.rate)));
      // ... and the activation dynamics with this excitation the planned activation rate.
      EXPECT_NEAR(fm::activation_derivative(p, inv.excitation, inv.activation), inv.activation_rate_per_s,
                  1e-9 * (1.0 + std::abs(inv.activation_rate_per_s)));
    }
  }
}

TEST(ExcitationBoundMargins, AreNonnegativeExactlyWhenTheExcitationIsInTheUnitInterval) {
  const auto p = triceps();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int inside = 0, outside = 0;
  for (int i = 0; i < 20000; ++i) {
    const double a = 1e-3 + (1.0 - 1e-3) * unit(rng);
    const double adot = (-40.0 + 140.0 * unit(rng)) * (0.05 + a);
    const fm::ExcitationBoundMargins m = fm::excitation_bound_margins(p, a, adot);
    const fm::ExcitationFromActivation n = fm::excitation_from_activation(p, a, adot);
    // Away from the boundary (where rounding decides), the two tests agree.
    if (std::min(std::abs(m.lower), std::abs(m.upper)) < 1e-9) continue;
    const bool margins_ok = m.lower >= 0.0 && m.upper >= 0.0;
    EXPECT_EQ(margins_ok, n.in_unit_interval()) << "a " << a << " da/dt " << adot << " n " << n.excitation;
    (margins_ok ? inside : outside)++;
  }
  EXPECT_GT(inside, 1000);
  EXPECT_GT(outside, 1000);
  // Their partial derivatives (away from the kink of the lower margin's curvature).
  for (double a : {0.05, 0.2, 0.5, 0.9})
    for (double adot : {-20.0, 0.0, 15.0}) {
      const auto m = fm::excitation_bound_margins(p, a, adot);
      auto at = [&](double x, double y, bool lower) {
        const auto v = fm::excitation_bound_margins(p, x, y);
        return lower ? v.lower : v.upper;
      };
      const double ha = default_step(a, 1.0), hr = default_step(adot, 1.0);
      EXPECT_MATCHES_FINITE_DIFFERENCE(m.lower_d_activation, central_difference([&](double x) { return at(x, adot, true); }, a, ha));
      EXPECT_MATCHES_FINITE_DIFFERENCE(m.upper_d_activation, central_difference([&](double x) { return at(x, adot, false); }, a, ha));
      EXPECT_MATCHES_FINITE_DIFFERENCE(m.lower_d_rate_s, central_difference([&](double y) { return at(a, y, true); }, adot, hr));
      EXPECT_MATCHES_FINITE_DIFFERENCE(m.upper_d_rate_s, central_difference([&](double y) { return at(a, y, false); }, adot, hr));
    }
}

TEST(MuscleInverse, SlackTendonAndNoForceCapacityStopTheChain) {
  const auto p = triceps();
  const fm::SecondOrderJet path{0.3, 0.0, 0.0};
  EXPECT_EQ(fm::invert_muscle(p, {0.0, 1.0, 0.0}, path, true).stage, fm::MuscleInverse::Stage::SlackTendon);
  EXPECT_EQ(fm::invert_muscle(p, {-3.0, 1.0, 0.0}, path, true).stage, fm::MuscleInverse::Stage::SlackTendon);
  // Shortening at Vmax (the path shortens that fast while the tendon holds its length).
  const double vmax = p.max_shortening_velocity_m_per_s();
  const fm::MuscleInverse fast = fm::invert_muscle(p, {100.0, 0.0, 0.0}, {0.3, -1.2 * vmax, 0.0}, true);
  EXPECT_EQ(fast.stage, fm::MuscleInverse::Stage::NoForceCapacity);
  EXPECT_NEAR(fast.shortening_velocity_m_per_s, 1.2 * vmax, 1e-12);
}

// Outside the domain the inverse says how far (>= 0, 0 inside) with gradients in both jets, so
// that the bounded planners can lead a start outside back in: a slack tendon (F <= 0), a
// collapsed pennated fibre (the tendon longer than the unit) and a fibre shortening faster than
// Vmax, each against finite differences; a step against the gradient shrinks the distance.
TEST(MuscleInverse, TheDistanceOutsideTheDomainHasExactGradients) {
  const auto plain = triceps();
  const auto pennated = variants()[1];
  const double vmax = plain.max_shortening_velocity_m_per_s();
  const double slack_path = plain.tendon_slack_length_m + plain.optimal_fiber_length_m;
  struct Case {
    const char* name;
    fm::MuscleParameters p;
    fm::SecondOrderJet force, path;
    fm::MuscleInverse::Stage stage;
  };
  const Case cases[] = {
      {"slack tendon", plain, {-30.0, 5.0, 1.0}, {slack_path, 0.1, 0.0}, fm::MuscleInverse::Stage::SlackTendon},
      {"collapsed fibre", pennated, {300.0, 40.0, -200.0}, {pennated.tendon_slack_length_m - 0.01, 0.05, 0.3},
       fm::MuscleInverse::Stage::FiberCollapsed},
      {"no force capacity", plain, {150.0, 300.0, 2e3}, {slack_path, -1.3 * vmax, 0.7}, fm::MuscleInverse::Stage::NoForceCapacity},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const fm::MuscleInverse inv = fm::invert_muscle(c.p, c.force, c.path, true);
    ASSERT_EQ(inv.stage, c.stage);
    EXPECT_GT(inv.domain_distance, 0.0);
    EXPECT_EQ(fm::invert_muscle(c.p, c.force, c.path, false).domain_distance, inv.domain_distance);
    double gradient_norm = 0.0;
    for (int k = 0; k < 6; ++k) {
      const bool on_force = k < 3;
      const int o = k % 3;
      auto distance = [&](double x) {
        fm::SecondOrderJet f = c.force, l = c.path;
        fm::SecondOrderJet& jet = on_force ? f : l;
        (o == 0 ? jet.value : o == 1 ? jet.rate : jet.acceleration) = x;
        return fm::invert_muscle(c.p, f, l, false).domain_distance;
      };
      const fm::SecondOrderJet& jet = on_force ? c.force : c.path;
      const double x0 = o == 0 ? jet.value : o == 1 ? jet.rate : jet.acceleration;
      const double analytic = on_force ? inv.domain_distance_gradient[o] : inv.path_domain_distance_gradient[o];
      EXPECT_MATCHES_FINITE_DIFFERENCE(analytic, central_difference(distance, x0, default_step(x0, on_force ? 1.0 : 1e-3)))
          << (on_force ? "d / dF" : "d / dL") << o;
      gradient_norm += analytic * analytic;
    }
    EXPECT_GT(gradient_norm, 0.0);
    // A small step down the gradient (in the force jet) moves toward the domain.
    fm::SecondOrderJet closer = c.force;
    const double s = 1e-3 * inv.domain_distance / std::max(1e-300, gradient_norm);
    closer.value -= s * inv.domain_distance_gradient[0];
    closer.rate -= s * inv.domain_distance_gradient[1];
    closer.acceleration -= s * inv.domain_distance_gradient[2];
    fm::SecondOrderJet path = c.path;
    path.value -= s * inv.path_domain_distance_gradient[0];
    path.rate -= s * inv.path_domain_distance_gradient[1];
    path.acceleration -= s * inv.path_domain_distance_gradient[2];
    EXPECT_LT(fm::invert_muscle(c.p, closer, path, false).domain_distance, inv.domain_distance);
  }
  // Inside the domain: 0.
  const fm::MuscleInverse inside = fm::invert_muscle(plain, {200.0, 0.0, 0.0}, {slack_path, 0.0, 0.0}, true);
  ASSERT_EQ(inside.stage, fm::MuscleInverse::Stage::Complete);
  EXPECT_EQ(inside.domain_distance, 0.0);
}

TEST(MuscleInverse, TheForceJetsGradientsAloneAreTheFullInversesBitForBit) {
  // Forward-mode components do not mix: seeding only the force's jet gives the same values and
  // force gradients as seeding all six, and leaves every path gradient 0. Inside the domain (every
  // variant) and outside it (slack tendon, collapsed fibre, no force capacity).
  auto expect_same = [](const fm::MuscleInverse& alone, const fm::MuscleInverse& full) {
    EXPECT_EQ(alone.stage, full.stage);
    EXPECT_EQ(alone.activation, full.activation);
    EXPECT_EQ(alone.activation_rate_per_s, full.activation_rate_per_s);
    EXPECT_EQ(alone.excitation, full.excitation);
    EXPECT_EQ(alone.domain_distance, full.domain_distance);
    EXPECT_EQ(alone.activation_gradient, full.activation_gradient);
    EXPECT_EQ(alone.activation_rate_gradient, full.activation_rate_gradient);
    EXPECT_EQ(alone.excitation_gradient, full.excitation_gradient);
    EXPECT_EQ(alone.domain_distance_gradient, full.domain_distance_gradient);
    const fm::PathLengthJetGradient zero{};
    EXPECT_EQ(alone.path_activation_gradient, zero);
    EXPECT_EQ(alone.path_activation_rate_gradient, zero);
    EXPECT_EQ(alone.path_excitation_gradient, zero);
    EXPECT_EQ(alone.path_domain_distance_gradient, zero);
  };
  int nonzero = 0;
  for (const auto& p : variants()) {
    SCOPED_TRACE(p.name);
    for (const Sample& s : samples(p, 20)) {
      const fm::MuscleInverse full = fm::invert_muscle(p, s.force, s.path, fm::InverseGradients::ForceAndPathJets);
      expect_same(fm::invert_muscle(p, s.force, s.path, fm::InverseGradients::ForceJet), full);
      nonzero += full.activation_rate_gradient[2] != 0.0;
    }
  }
  EXPECT_GT(nonzero, 100);  // the gradients compared are not all 0
  const auto plain = triceps();
  const auto pennated = variants()[1];
  const double slack_path = plain.tendon_slack_length_m + plain.optimal_fiber_length_m;
  const double vmax = plain.max_shortening_velocity_m_per_s();
  const std::tuple<fm::MuscleParameters, fm::SecondOrderJet, fm::SecondOrderJet> outside[] = {
      {plain, {-30.0, 5.0, 1.0}, {slack_path, 0.1, 0.0}},
      {pennated, {300.0, 40.0, -200.0}, {pennated.tendon_slack_length_m - 0.01, 0.05, 0.3}},
      {plain, {150.0, 300.0, 2e3}, {slack_path, -1.3 * vmax, 0.7}}};
  for (const auto& [p, force, path] : outside) {
    const fm::MuscleInverse full = fm::invert_muscle(p, force, path, fm::InverseGradients::ForceAndPathJets);
    ASSERT_NE(full.stage, fm::MuscleInverse::Stage::Complete);
    expect_same(fm::invert_muscle(p, force, path, fm::InverseGradients::ForceJet), full);
  }
}
