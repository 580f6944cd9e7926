// Unit mix-ups are reported as warnings naming the field: each implausible value of a model in
// SI units gives exactly one warning, a model in SI units none; joint angles beyond one turn
// likewise. Impossible values are errors elsewhere (model validation, the planner's postures).
#include <gtest/gtest.h>

#include <functional>

#include "arm_fixture.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/model/plausibility.hpp"

namespace fp = flatsos::plugin;

TEST(Plausibility, TheShippedModelsInSiUnitsHaveNoWarnings) {
  for (const char* file :
       {"arm_richter_warner.json", "elbow_1dof.json", "elbow_posture_dependent.json", "arm_wrist_8_muscles.json"}) {
    const auto d = fp::load_model_file(std::string(FLATSOS_SOURCE_DIR) + "/models/" + file);
    EXPECT_TRUE(fp::plausibility_warnings(d).empty()) << file << ": " << fp::plausibility_warnings(d).front();
    EXPECT_TRUE(fp::MusculoskeletalModel(d).warnings().empty());
  }
}

TEST(Plausibility, EachValueInTheWrongUnitGivesOneWarningNamingItsField) {
  struct Case {
    std::function<void(fp::ModelDescription&)> change;
    std::string field;
  };
  const std::vector<Case> cases = {
      {[](auto& d) { d.muscles[2].moment_arms_m[1] = 3.0; }, "muscles[2] 'biceps'.moment_arms_m.elbow: 3 m is above 0.2 m"},
      {[](auto& d) { d.muscles[0].moment_arms_m[0] = -5.0; }, "muscles[0] 'anterior_deltoid'.moment_arms_m.shoulder: 5 m"},
      {[](auto& d) {
         // The same in a polynomial path (OpenSim's order: 1, elbow, shoulder).
         d.muscles[2].moment_arms_m.resize(0);
         d.muscles[2].length_at_zero_angles_m = 0.0;
         d.muscles[2].polynomial_path = fp::PolynomialPathDescription{{"shoulder", "elbow"}, 1, {0.43, -3.0, -0.03}, {}};
       },
       "muscles[2] 'biceps'.path: moment arm about elbow at mid-range: 3 m is above 0.2 m"},
      {[](auto& d) { d.muscles[5].parameters.optimal_fiber_length_m = 102.8; }, "muscles[5] 'brachialis'.optimal_fiber_length_m: 102.8 m"},
      {[](auto& d) { d.muscles[3].parameters.tendon_slack_length_m = 190.5; }, "muscles[3] 'triceps_long'.tendon_slack_length_m"},
      {[](auto& d) { d.muscles[1].length_at_zero_angles_m = 105.5; }, "muscles[1] 'posterior_deltoid'.length_at_zero_angles_m"},
      {[](auto& d) { d.muscles[4].parameters.max_isometric_force_N = 7e5; }, "muscles[4] 'triceps_short'.max_isometric_force_N"},
      {[](auto& d) { d.bodies[1].mass_kg = 1760.0; }, "bodies[1] 'forearm'.mass_kg: 1760 kg"},
      {[](auto& d) { d.bodies[0].length_m = 33.0; }, "bodies[0] 'upper_arm'.length_m: 33 m"},
      {[](auto& d) { d.gravity_m_per_s2 = Eigen::Vector3d(0, -981, 0); }, "gravity_m_per_s2: 981 m/s^2"},
  };
  for (const auto& c : cases) {
    auto d = fp::load_model_file(flatsos::test::arm_model_path());
    c.change(d);
    const auto warnings = fp::plausibility_warnings(d);
    ASSERT_EQ(warnings.size(), 1u) << c.field;
    EXPECT_EQ(warnings[0].rfind(c.field, 0), 0u) << warnings[0];
    EXPECT_EQ(fp::MusculoskeletalModel(d).warnings(), warnings);  // possible values: the model builds and keeps them
  }
}

TEST(Plausibility, JointAnglesBeyondOneTurnAreNamedPerJoint) {
  const auto d = fp::load_model_file(flatsos::test::arm_model_path());
  EXPECT_TRUE(fp::joint_angle_warnings(d, Eigen::Vector2d(1.5, -6.2), "target").empty());
  const auto w = fp::joint_angle_warnings(d, Eigen::Vector2d(90.0, 0.1), "target joint angles");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0], "target joint angles.shoulder: 90 rad is beyond one turn (degrees given as radians?)");
  EXPECT_EQ(fp::joint_angle_warnings(d, Eigen::Vector2d(-7.0, 7.0), "q").size(), 2u);
}
