// The effort seam: each effort's term against finite differences, its names, and its errors.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "flatsos/planner/effort.hpp"

namespace fpl = flatsos::planner;

namespace {

flatsos::muscles::MuscleParameters muscle() {
  flatsos::muscles::MuscleParameters p;
  p.name = "m";
  p.max_isometric_force_N = 800.0;
  p.optimal_fiber_length_m = 0.1;
  p.tendon_slack_length_m = 0.2;
  return p;
}

// d/dx of f by central differences.
template <class F>
double difference(F f, double x, double h) {
  return (f(x + h) - f(x - h)) / (2.0 * h);
}

}  // namespace

TEST(Effort, EveryNamedEffortsDerivativesMatchDifferences) {
  const Eigen::VectorXd w = Eigen::Vector2d(0.5, 2.0);
  const auto p = muscle();
  for (const std::string& name : fpl::effort_names()) {
    const auto effort = fpl::effort_named(name, w);
    EXPECT_EQ(effort->name(), name);
    EXPECT_NO_THROW(effort->validate(2));
    const double F = 300.0, a = 0.4, n = 0.7;
    const fpl::MuscleEffortJet t = effort->muscleTerm(1, p, F, a, n);
    auto at = [&](double f, double x, double y) { return effort->muscleTerm(1, p, f, x, y); };
    EXPECT_NEAR(t.d_force, difference([&](double y) { return at(y, a, n).value; }, F, 1e-3), 1e-8) << name;
    EXPECT_NEAR(t.d_activation, difference([&](double y) { return at(F, y, n).value; }, a, 1e-6), 1e-8) << name;
    EXPECT_NEAR(t.d_excitation, difference([&](double y) { return at(F, a, y).value; }, n, 1e-6), 1e-8) << name;
    EXPECT_NEAR(t.d_force2, difference([&](double y) { return at(y, a, n).d_force; }, F, 1e-3), 1e-10) << name;
    EXPECT_NEAR(t.d_activation2, difference([&](double y) { return at(F, y, n).d_activation; }, a, 1e-6), 1e-7) << name;
    EXPECT_NEAR(t.d_excitation2, difference([&](double y) { return at(F, a, y).d_excitation; }, n, 1e-6), 1e-7) << name;
  }
}

TEST(Effort, ValuesAreTheFieldsDefinitions) {
  const auto p = muscle();
  // Moco's MocoControlGoal: w n^2; static optimization: a^2 or a^3; stress: (F / Fmax)^p.
  EXPECT_DOUBLE_EQ(fpl::effort_named("excitation_squared")->muscleTerm(0, p, 100.0, 0.3, 0.5).value, 0.25);
  EXPECT_DOUBLE_EQ(fpl::effort_named("activation_cubed")->muscleTerm(0, p, 100.0, 0.3, 0.5).value, 0.027);
  EXPECT_DOUBLE_EQ(fpl::effort_named("stress_squared")->muscleTerm(0, p, 400.0, 0.3, 0.5).value, 0.25);
  EXPECT_DOUBLE_EQ(fpl::effort_named("tendon_force", Eigen::VectorXd::Constant(1, 2.0))->muscleTerm(0, p, 100.0, 0.3, 0.5).value,
                   200.0);
  // Only the tendon-force effort is linear in F, with its weights.
  EXPECT_TRUE(fpl::effort_named("tendon_force", Eigen::VectorXd::Ones(3))->tendonForceWeights().has_value());
  EXPECT_FALSE(fpl::effort_named("stress_squared")->tendonForceWeights().has_value());
  EXPECT_EQ(fpl::effort_named("tendon_force", Eigen::VectorXd::Ones(3))->unit(), "N s");
  EXPECT_EQ(fpl::effort_named("activation_squared")->unit(), "s");
  EXPECT_EQ(fpl::PowerEffort(fpl::PowerEffort::Quantity::Activation, 2.5).name(), "activation_power_2.5");
}

TEST(Effort, BadNamesAndWeightsAreNamedInTheError) {
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([] { fpl::effort_named("effort"); }).find("excitation_squared"), std::string::npos);
  EXPECT_NE(message([] { fpl::effort_named("tendon_force")->validate(3); }).find("one weight per muscle (3), got 0"),
            std::string::npos);
  EXPECT_NE(message([] { fpl::effort_named("excitation_squared", Eigen::Vector2d(1.0, -1.0))->validate(2); })
                .find("weight 1 must be finite and >= 0"),
            std::string::npos);
  EXPECT_NE(message([] { fpl::effort_named("excitation_squared", Eigen::Vector2d::Zero())->validate(2); })
                .find("nothing to minimize"),
            std::string::npos);
  EXPECT_NE(message([] { fpl::PowerEffort(fpl::PowerEffort::Quantity::Excitation, 0.5); }).find("exponent"),
            std::string::npos);
  EXPECT_NO_THROW(fpl::effort_named("excitation_squared")->validate(4));  // no weights: 1 each
}
