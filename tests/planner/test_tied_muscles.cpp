// Tied muscles: two elbow extensors with the same moment arms and the same effort weight (arm26's
// TRIlat and TRImed). A linear effort prices every split of their load alike; the planner must
// still plan, keep the bounds, and not shuttle the load between them.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <optional>
#include <string>

#include "../plugin/arm_fixture.hpp"
#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/open_loop.hpp"
#include "flatsos/planner/rest_state.hpp"

namespace fpl = flatsos::planner;
using flatsos::test::deg;

namespace {
// The paper's arm without deltoids (the biceps and the long triceps hold the shoulder, so the
// elbow's flexors and extensors co-contract), its short triceps split into two heads of 700 N
// with the same moment arm and tendons 5.5 mm apart: muscles 1 and 2.
constexpr int kLateral = 1, kMedial = 2;

std::shared_ptr<const flatsos::plugin::MusculoskeletalModel> tied_arm() {
  return flatsos::plugin::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) +
                                                          "/tests/data/arm_tied_triceps.json");
}

fpl::OpenLoopPlan plan_from_rest(const fpl::FlatOutputMap& flat, const Eigen::Vector2d& q0_rad,
                                 const Eigen::Vector2d& target_rad) {
  const Eigen::VectorXd reserves_N = Eigen::VectorXd::Constant(flat.numMuscles(), 10.0);
  const SimTK::State s0 = fpl::start_state(flat, q0_rad, Eigen::Vector2d::Zero(), std::nullopt, reserves_N);
  fpl::OpenLoopOptions o = fpl::open_loop_options(fpl::Preset::Best);
  o.duration_s = 1.0;
  o.target_q_rad = target_rad;
  o.reserves_N = reserves_N;
  return fpl::plan_open_loop(flat, fpl::muscle_state_of(flat.model(), s0), o);
}

// Total variations over a fine grid of the tied heads' summed force and of their split.
struct SplitVariation {
  double sum_N = 0.0, split_N = 0.0;
};

SplitVariation split_variation(const fpl::FlatOutputMap& flat, const fpl::OpenLoopPlan& plan) {
  SplitVariation v;
  double last_sum = 0.0, last_split = 0.0;
  constexpr int kPoints = 1001;
  for (int i = 0; i < kPoints; ++i) {
    const double t = plan.path.duration_s * i / (kPoints - 1);
    const Eigen::VectorXd F = flat.inverse(plan.jointJet(t), plan.flatOutputJet(t)).tendon_force_N;
    const double sum = F[kLateral] + F[kMedial], split = F[kLateral] - F[kMedial];
    if (i > 0) {
      v.sum_N += std::abs(sum - last_sum);
      v.split_N += std::abs(split - last_split);
    }
    last_sum = sum;
    last_split = split;
  }
  return v;
}
}  // namespace

TEST(TiedMuscles, OnlyMusclesWithTheSameMomentArmsAndWeightArePricedApart) {
  const fpl::FlatOutputMap tied(tied_arm());
  const Eigen::VectorXd& w = tied.effortWeights();
  const Eigen::VectorXd& priced = tied.effortPricingWeights();
  EXPECT_DOUBLE_EQ(w[kLateral], 1.0 / 700.0);  // 1 / Fmax: the library chose E
  EXPECT_DOUBLE_EQ(priced[kLateral], 1.001 / 700.0);
  EXPECT_DOUBLE_EQ(priced[kMedial], 1.0 / 700.0);
  for (int j : {0, 3, 4}) EXPECT_EQ(priced[j], w[j]) << j;
  // The same heads 1 % apart in strength weigh differently: no tie.
  auto description = tied_arm()->description();
  description.muscles[kMedial].parameters.max_isometric_force_N = 707.0;
  const fpl::FlatOutputMap untied(std::make_shared<const flatsos::plugin::MusculoskeletalModel>(description));
  EXPECT_EQ(untied.effortPricingWeights(), untied.effortWeights());
}

TEST(TiedMuscles, BoundedPlansWithTiedExtensorsSolveWithoutShuttlingTheirLoad) {
  const fpl::FlatOutputMap flat(tied_arm());
  for (const auto& [q0, target] : {std::pair{Eigen::Vector2d(0.0, deg(10)), Eigen::Vector2d(deg(30), deg(60))},
                                   std::pair{Eigen::Vector2d(0.0, deg(60)), Eigen::Vector2d(0.0, deg(60))}}) {
    SCOPED_TRACE("to " + std::to_string(target[0]) + ", " + std::to_string(target[1]) + " rad");
    const fpl::OpenLoopPlan plan = plan_from_rest(flat, q0, target);
    ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
    EXPECT_EQ(plan.check.points_outside_domain, 0) << plan.check.first_violation;
    EXPECT_GE(plan.check.min_excitation, -1e-8);
    EXPECT_LE(plan.check.max_excitation, 1.0 + 1e-8);
    EXPECT_GE(plan.check.min_reserve_margin_N, -1e-6);
    // A split that shuttles the load between the heads varies far more than the load itself;
    // one head at its reserve while the other carries the rest varies exactly as much.
    const SplitVariation v = split_variation(flat, plan);
    EXPECT_LE(v.split_N, 1.05 * v.sum_N + 1.0) << "sum varies " << v.sum_N << " N";
  }
}
