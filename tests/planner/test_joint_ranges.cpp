// A start or target outside a joint's range is refused naming the joint; a planned path that
// leaves the range is a warning naming the joint, how far and when.
#include <gtest/gtest.h>

#include <cmath>

#include "flatness/input_checks.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "scenario_fixture.hpp"

namespace fpl = flatsos::planner;

namespace {

flatsos::plugin::ModelDescription arm_with_elbow_range(double lower_rad, double upper_rad) {
  auto d = flatsos::plugin::load_model_file(flatsos::test::arm_model_path());
  d.joints[1].range_rad = {lower_rad, upper_rad};
  return d;
}

// From rest at (0, 1) rad with the elbow at 20 rad/s, to rest at (0, 2.4) rad in 1 s: the quintic
// overshoots 2.4.
fpl::JointPath overshooting_path() {
  Eigen::MatrixXd initial(2, 3), terminal(2, 3);
  initial << 0, 0, 0, 1.0, 20.0, 0;
  terminal << 0, 0, 0, 2.4, 0, 0;
  return fpl::fit_joint_path(1.0, initial, terminal);
}

}  // namespace

TEST(JointRanges, AnAngleOutsideARangeIsRefusedNamingTheJointInDegrees) {
  const auto d = arm_with_elbow_range(0.0, 2.5);
  EXPECT_NO_THROW(fpl::detail::require_within_joint_ranges(d, Eigen::Vector2d(-3.0, 2.5),
                                                           "target joint angles"));
  try {
    fpl::detail::require_within_joint_ranges(d, Eigen::Vector2d(0.0, 2.6), "target joint angles");
    FAIL() << "2.6 rad accepted in [0, 2.5]";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(
        e.what(),
        "target joint angles: joint 'elbow' at 148.969 deg is outside its range [0, 143.239] deg "
        "(the model's \"range_rad\")");
  }
}

TEST(JointRanges, ASoftStopMayBePressedInto) {
  auto d = arm_with_elbow_range(0.0, 2.5);
  d.joints[1].limit.stiffness_N_m_per_rad = 100.0;
  d.joints[1].limit.transition_rad = 0.1;
  EXPECT_NO_THROW(fpl::detail::require_within_joint_ranges(d, Eigen::Vector2d(0.0, 2.6),
                                                           "target joint angles"));
  EXPECT_TRUE(fpl::detail::joint_range_warnings(d, overshooting_path(), 1.0, 1001).empty());
}

TEST(JointRanges, APathLeavingTheRangeWarnsHowFarAndWhen) {
  const fpl::JointPath path = overshooting_path();
  // The overshoot, found independently on a finer grid.
  double peak = -1.0, peak_t = 0.0;
  for (int k = 0; k <= 10000; ++k) {
    const double t = k * 1e-4, q = path.jet(t, 1)(1, 0);
    if (q > peak) peak = q, peak_t = t;
  }
  ASSERT_GT(peak, 2.5);
  const auto warnings =
      fpl::detail::joint_range_warnings(arm_with_elbow_range(0.0, 2.5), path, 1.0, 1001);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("leaves the range [0, 143.239] deg of joint 'elbow' by up to "),
            std::string::npos);
  const double shown_deg = std::stod(warnings[0].substr(warnings[0].find("by up to ") + 9));
  EXPECT_NEAR(shown_deg, (peak - 2.5) * 180.0 / M_PI, 0.05);
  const double shown_t = std::stod(warnings[0].substr(warnings[0].find("t = ") + 4));
  EXPECT_NEAR(shown_t, peak_t, 1e-3);
  EXPECT_TRUE(
      fpl::detail::joint_range_warnings(arm_with_elbow_range(0.0, peak + 1e-6), path, 1.0, 1001)
          .empty());
  // Rounding at a range's end is not leaving it (a path that starts exactly there).
  EXPECT_TRUE(
      fpl::detail::joint_range_warnings(arm_with_elbow_range(0.0, peak - 1e-12), path, 1.0, 1001)
          .empty());
  EXPECT_NO_THROW(fpl::detail::require_within_joint_ranges(
      arm_with_elbow_range(0.0, 2.5), Eigen::Vector2d(0.0, -1e-13), "start joint angles (q0)"));
}
