// Parameter validation names the muscle and the field, and rejects every non-physical value.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/muscles/muscle_parameters.hpp"

namespace fm = flatsos::muscles;

namespace {
fm::MuscleParameters valid() {
  fm::MuscleParameters p;
  p.name = "brachialis";
  p.max_isometric_force_N = 700.0;
  p.optimal_fiber_length_m = 0.1028;
  p.tendon_slack_length_m = 0.0175;
  return p;
}

struct Case {
  const char* field;
  std::function<void(fm::MuscleParameters&)> spoil;
};
}  // namespace

TEST(MuscleParameters, ValidParametersPassAndDerivedQuantitiesAreRight) {
  const auto p = valid();
  EXPECT_NO_THROW(fm::validate(p));
  EXPECT_NEAR(p.max_shortening_velocity_m_per_s(), 1.028, 1e-15);
  EXPECT_NEAR(p.activation_beta(), 0.25, 1e-15);
  EXPECT_NEAR(fm::tendon_force(p, 1.04 * p.tendon_slack_length_m), 700.0, 1e-9);
}

TEST(MuscleParameters, EveryBadFieldIsRejectedByName) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const Case cases[] = {
      {"max_isometric_force_N", [](auto& p) { p.max_isometric_force_N = 0.0; }},
      {"max_isometric_force_N", [](auto& p) { p.max_isometric_force_N = -5.0; }},
      {"max_isometric_force_N", [nan](auto& p) { p.max_isometric_force_N = nan; }},
      {"optimal_fiber_length_m", [](auto& p) { p.optimal_fiber_length_m = -0.1; }},
      {"optimal_fiber_length_m", [inf](auto& p) { p.optimal_fiber_length_m = inf; }},
      {"tendon_slack_length_m", [](auto& p) { p.tendon_slack_length_m = 0.0; }},
      {"tendon_strain_at_max_force", [](auto& p) { p.tendon_strain_at_max_force = 0.0; }},
      {"force_length_width", [](auto& p) { p.force_length_width = -1.0; }},
      {"max_shortening_velocity_in_optimal_lengths_per_s",
       [](auto& p) { p.max_shortening_velocity_in_optimal_lengths_per_s = 0.0; }},
      {"hill_constant", [nan](auto& p) { p.hill_constant = nan; }},
      {"max_eccentric_force_ratio", [](auto& p) { p.max_eccentric_force_ratio = 1.0; }},
      {"max_eccentric_force_ratio", [](auto& p) { p.max_eccentric_force_ratio = 0.5; }},
      {"activation_time_constant_s", [](auto& p) { p.activation_time_constant_s = 0.0; }},
      {"deactivation_time_constant_s", [](auto& p) { p.deactivation_time_constant_s = -0.04; }},
      {"activation_time_constant_s", [](auto& p) { p.activation_time_constant_s = 0.1; }},
      {"activation_floor", [](auto& p) { p.activation_floor = 0.0; }},
      {"activation_floor", [](auto& p) { p.activation_floor = 1.0; }},
      {"activation_floor", [nan](auto& p) { p.activation_floor = nan; }},
  };
  for (const auto& c : cases) {
    auto p = valid();
    c.spoil(p);
    try {
      fm::validate(p);
      ADD_FAILURE() << "accepted a bad " << c.field;
    } catch (const std::invalid_argument& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("brachialis"), std::string::npos) << msg;
      EXPECT_NE(msg.find(c.field), std::string::npos) << msg;
    }
  }
}
