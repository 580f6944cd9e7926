// Flat outputs the library chooses when a model gives none: the chosen E satisfies Assumption 1
// over the joint ranges with the largest margin of every combination of its candidate rows (an
// exhaustive enumeration here, margins computed independently: C_Y(q) 1 from a QR solve of
// [R(q); E] v = [0; 1]); the margin it reports is the one a dense grid gives; the effort then
// defaults to normalized tendon forces; and models where no E can hold say why.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/model/posture_grid.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;

namespace {

fp::ModelDescription shipped(const std::string& file) {
  return fp::load_model_file(std::string(FLATSOS_SOURCE_DIR) + "/models/" + file);
}

std::shared_ptr<const fp::MusculoskeletalModel> without_flat_outputs(fp::ModelDescription d) {
  d.flat_outputs.clear();
  return std::make_shared<const fp::MusculoskeletalModel>(d);
}

// The postures of the library's grid (posture_grid.hpp) with about `budget` of them.
std::vector<Eigen::VectorXd> grid(const fp::MusculoskeletalModel& model, long budget) {
  std::vector<Eigen::VectorXd> out;
  if (model.hasConstantMomentArms()) return {Eigen::VectorXd::Zero(model.numJoints())};
  const fp::ModelDescription& d = model.description();
  fp::for_each_posture(d, fp::posture_dependent_joints(d), budget, [&](const Eigen::VectorXd& q) { out.push_back(q); });
  return out;
}

// v = C_Y(q) 1 solved independently of the library's LU: R v = 0, E v = 1 by pivoted QR.
Eigen::VectorXd unit_flat_output_forces(const Eigen::MatrixXd& R, const Eigen::MatrixXd& E) {
  Eigen::MatrixXd C(R.cols(), R.cols());
  C << R, E;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(R.cols());
  rhs.tail(E.rows()).setOnes();
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(C);
  if (qr.rank() < C.rows()) return Eigen::VectorXd::Constant(R.cols(), -1e300);
  return qr.solve(rhs);
}

// The smallest entry of v over the postures (-1e300 where C is singular); stops below `bar`.
double margin(const std::vector<Eigen::MatrixXd>& R, const Eigen::MatrixXd& E, double bar = -1e301) {
  double smallest = 1e300;
  for (const Eigen::MatrixXd& r : R) {
    smallest = std::min(smallest, unit_flat_output_forces(r, E).minCoeff());
    if (smallest < bar) break;
  }
  return smallest;
}

// The best margin of every p-subset of the candidate rows, enumerated.
double best_margin_of_every_combination(const Eigen::MatrixXd& candidates, int p, const std::vector<Eigen::MatrixXd>& R) {
  const int count = static_cast<int>(candidates.rows());
  std::vector<int> pick(static_cast<std::size_t>(p));
  for (int i = 0; i < p; ++i) pick[static_cast<std::size_t>(i)] = i;
  double best = -1e301;
  Eigen::MatrixXd E(p, candidates.cols());
  while (true) {
    for (int i = 0; i < p; ++i) E.row(i) = candidates.row(pick[static_cast<std::size_t>(i)]);
    best = std::max(best, margin(R, E, best));
    int i = p - 1;
    while (i >= 0 && pick[static_cast<std::size_t>(i)] == count - p + i) --i;
    if (i < 0) return best;
    ++pick[static_cast<std::size_t>(i)];
    for (int k = i + 1; k < p; ++k) pick[static_cast<std::size_t>(k)] = pick[static_cast<std::size_t>(k - 1)] + 1;
  }
}

std::vector<Eigen::MatrixXd> moment_arms_on(const fp::MusculoskeletalModel& model, const std::vector<Eigen::VectorXd>& q) {
  std::vector<Eigen::MatrixXd> R;
  for (const auto& posture : q) R.push_back(model.momentArmMatrix(posture));
  return R;
}

// The library's tie-break between equal margins, computed here without its early stops: the
// largest 1-norm condition number estimate of [R(q); E] over the postures, R's rows at unit length.
double condition_number(const std::vector<Eigen::MatrixXd>& R, const Eigen::MatrixXd& E) {
  double worst = 0.0;
  for (const Eigen::MatrixXd& r : R) {
    Eigen::MatrixXd C(r.cols(), r.cols());
    C << r.rowwise().normalized(), E;
    worst = std::max(worst, 1.0 / Eigen::PartialPivLU<Eigen::MatrixXd>(C).rcond());
  }
  return worst;
}
}  // namespace

TEST(FlatOutputChoice, TheChosenEHasTheLargestMarginOfEveryCombinationOfItsCandidates) {
  // The arm (constant moment arms, 14 candidates, p = 4), the 3-muscle elbow (constant), the
  // posture-dependent elbow and the 3-joint arm with 8 muscles (posture-dependent, 18 candidates,
  // p = 5: the default search exchanges rows there).
  for (const char* file : {"arm_richter_warner.json", "elbow_1dof.json", "elbow_posture_dependent.json", "arm_wrist_8_muscles.json"}) {
    SCOPED_TRACE(file);
    const auto model = without_flat_outputs(shipped(file));
    const int p = model->numMuscles() - model->numJoints();
    fpl::FlatOutputSearchOptions options;
    const std::vector<Eigen::MatrixXd> R_search = moment_arms_on(*model, grid(*model, options.search_postures));
    const fpl::FlatOutputCandidates candidates = fpl::flat_output_candidates(*model, options.search_postures);
    const double best = best_margin_of_every_combination(candidates.rows, p, R_search);
    ASSERT_GT(best, 0.0);
    for (bool exchange : {false, true}) {
      SCOPED_TRACE(exchange ? "exchange search" : "default search");
      options.force_exchange_search = exchange;
      const fpl::FlatOutputChoice choice = fpl::choose_flat_outputs(*model, options);
      EXPECT_TRUE(choice.automatic);
      ASSERT_EQ(choice.E.rows(), p);
      ASSERT_EQ(choice.names.size(), static_cast<std::size_t>(p));
      EXPECT_GE(choice.E.minCoeff(), 0.0);  // weighted means of tendon forces
      EXPECT_LT((choice.E.rowwise().sum() - Eigen::VectorXd::Ones(p)).cwiseAbs().maxCoeff(), 1e-15);
      EXPECT_NEAR(margin(R_search, choice.E), best, 1e-9);
      // The reported margin is the dense grid's, where it says it is.
      const std::vector<Eigen::VectorXd> dense = grid(*model, options.final_postures);
      EXPECT_NEAR(choice.margin.margin, margin(moment_arms_on(*model, dense), choice.E), 1e-12);
      ASSERT_GE(choice.margin.muscle, 0);
      EXPECT_NEAR(unit_flat_output_forces(model->momentArmMatrix(choice.margin.posture_rad), choice.E)[choice.margin.muscle],
                  choice.margin.margin, 1e-12);
      EXPECT_TRUE(std::isfinite(choice.margin.condition_number));
      EXPECT_GE(choice.margin.condition_number, 1.0);
    }
  }
}

TEST(FlatOutputChoice, BetweenEqualMarginsTheSmallestConditionNumberWins) {
  // Margins tie often (at 1, the most a nonnegative E allows, whenever single-muscle rows leave
  // every other muscle at least as taut): the search stops a score as soon as it can no longer
  // beat the best one, by margin or by condition number. Every combination scored here in full.
  // The arm: 527 of 715 combinations tie at the best margin; the 8-muscle arm: 379 of 8568.
  for (const char* file : {"arm_richter_warner.json", "arm_wrist_8_muscles.json"}) {
    SCOPED_TRACE(file);
    const auto model = without_flat_outputs(shipped(file));
    const int p = model->numMuscles() - model->numJoints();
    const fpl::FlatOutputSearchOptions options;
    const std::vector<Eigen::MatrixXd> R = moment_arms_on(*model, grid(*model, options.search_postures));
    const Eigen::MatrixXd candidates = fpl::flat_output_candidates(*model, options.search_postures).rows;
    const int count = static_cast<int>(candidates.rows());
    std::vector<int> pick(static_cast<std::size_t>(p));
    for (int i = 0; i < p; ++i) pick[static_cast<std::size_t>(i)] = i;
    std::vector<std::pair<double, double>> scores;  // (margin, condition number)
    Eigen::MatrixXd E(p, candidates.cols());
    while (true) {
      for (int i = 0; i < p; ++i) E.row(i) = candidates.row(pick[static_cast<std::size_t>(i)]);
      scores.emplace_back(margin(R, E), condition_number(R, E));
      int i = p - 1;
      while (i >= 0 && pick[static_cast<std::size_t>(i)] == count - p + i) --i;
      if (i < 0) break;
      ++pick[static_cast<std::size_t>(i)];
      for (int k = i + 1; k < p; ++k) pick[static_cast<std::size_t>(k)] = pick[static_cast<std::size_t>(k - 1)] + 1;
    }
    double best_margin = -1e301;
    for (const auto& s : scores) best_margin = std::max(best_margin, s.first);
    double best_condition = 1e301;
    int tied = 0;
    for (const auto& s : scores)
      if (std::abs(s.first - best_margin) <= 1e-9) best_condition = std::min(best_condition, s.second), ++tied;
    ASSERT_GT(tied, 1) << "no tie to break";
    const fpl::FlatOutputChoice choice = fpl::choose_flat_outputs(*model, options);
    EXPECT_NEAR(margin(R, choice.E), best_margin, 1e-9);
    EXPECT_NEAR(condition_number(R, choice.E), best_condition, 1e-9 * best_condition);
  }
}

TEST(FlatOutputChoice, TheLibrarysEHoldsAtLeastAsWellAsTheHandWrittenOnes) {
  // The 3-muscle elbow (arms 0.03, 0.03, -0.03 m): the paper-style E (biceps-triceps mean,
  // brachialis) gives v = (1/2, 1, 3/2), margin 1/2; single rows of the two flexors give
  // v = (1, 1, 2), margin 1, the most a nonnegative E allows (E v = 1 makes some v_j <= 1).
  for (const char* file : {"arm_richter_warner.json", "elbow_1dof.json", "elbow_posture_dependent.json"}) {
    SCOPED_TRACE(file);
    const fp::ModelDescription d = shipped(file);
    const fpl::FlatOutputMap given(std::make_shared<const fp::MusculoskeletalModel>(d));
    const fpl::FlatOutputMap chosen(without_flat_outputs(d));
    EXPECT_FALSE(given.flatOutputs().automatic);
    EXPECT_TRUE(chosen.flatOutputs().automatic);
    EXPECT_GE(chosen.flatOutputs().margin.margin, given.flatOutputs().margin.margin - 1e-12);
    EXPECT_LE(chosen.flatOutputs().margin.margin, 1.0 + 1e-12);
  }
  const fpl::FlatOutputMap elbow_given(std::make_shared<const fp::MusculoskeletalModel>(shipped("elbow_1dof.json")));
  EXPECT_NEAR(elbow_given.flatOutputs().margin.margin, 0.5, 1e-14);
  EXPECT_EQ(elbow_given.flatOutputs().names[0], "elbow_cocontraction");
  const fpl::FlatOutputMap elbow_chosen(without_flat_outputs(shipped("elbow_1dof.json")));
  EXPECT_NEAR(elbow_chosen.flatOutputs().margin.margin, 1.0, 1e-14);
  EXPECT_EQ(elbow_chosen.flatOutputs().names, (std::vector<std::string>{"biceps_force", "brachialis_force"}));
}

TEST(FlatOutputChoice, TheEffortDefaultsToNormalizedTendonForcesWhenTheLibraryChoosesE) {
  fp::ModelDescription d = shipped("elbow_1dof.json");
  EXPECT_EQ(fpl::FlatOutputMap(std::make_shared<const fp::MusculoskeletalModel>(d)).effortKind(),
            fp::EffortWeights::Kind::FlatOutputs);
  const fpl::FlatOutputMap chosen(without_flat_outputs(d));
  EXPECT_EQ(chosen.effortKind(), fp::EffortWeights::Kind::NormalizedTendonForce);
  EXPECT_FALSE(chosen.effortIsFlatOutputSum());
  for (int j = 0; j < 3; ++j)
    EXPECT_EQ(chosen.effortWeights()[j], 1.0 / d.muscles[static_cast<std::size_t>(j)].parameters.max_isometric_force_N);
  // Asked for explicitly, the flat outputs' sum stays available with the library's E.
  d.effort_weights.kind = fp::EffortWeights::Kind::FlatOutputs;
  const fpl::FlatOutputMap sum(without_flat_outputs(d));
  EXPECT_TRUE(sum.effortIsFlatOutputSum());
  EXPECT_LT((sum.effortWeights() - sum.E().transpose() * Eigen::VectorXd::Ones(2)).norm(), 1e-15);
}

TEST(FlatOutputChoice, AnotherModelKeepsTheChoiceAndItsKindOfEffort) {
  fp::ModelDescription d = shipped("elbow_1dof.json");
  const fpl::FlatOutputMap chosen(without_flat_outputs(d));
  d.flat_outputs.clear();
  for (auto& muscle : d.muscles) muscle.parameters.max_isometric_force_N *= 1.3;
  const auto stronger = std::make_shared<const fp::MusculoskeletalModel>(d);
  const fpl::FlatOutputMap moved = chosen.withModel(stronger);
  EXPECT_EQ(&moved.model(), stronger.get());
  EXPECT_EQ(moved.E(), chosen.E());
  EXPECT_EQ(moved.flatOutputs().names, chosen.flatOutputs().names);
  EXPECT_TRUE(moved.flatOutputs().automatic);
  // Still the normalized tendon force, now of the new maximum forces (E alone would have
  // made it the flat outputs' sum).
  EXPECT_EQ(moved.effortKind(), fp::EffortWeights::Kind::NormalizedTendonForce);
  for (int j = 0; j < 3; ++j)
    EXPECT_DOUBLE_EQ(moved.effortWeights()[j], chosen.effortWeights()[j] / 1.3);
  EXPECT_EQ(fpl::FlatOutputMap(stronger, chosen.E()).effortKind(), fp::EffortWeights::Kind::FlatOutputs);
  const auto arm = std::make_shared<const fp::MusculoskeletalModel>(shipped("arm_richter_warner.json"));
  try {
    (void)chosen.withModel(arm);
    FAIL() << "a model of other size was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "flat outputs of a model of 1 joints and 3 muscles given to one of 2 and 6");
  }
}

TEST(FlatOutputChoice, AModelNoFlatOutputsCanServeSaysWhy) {
  const std::string body = R"("bodies": [{"name": "forearm", "mass_kg": 1.5, "mass_center_m": [0.17, 0, 0], "inertia_about_mass_center_kg_m2": 0.02}],
    "joints": [{"name": "elbow", "type": "pin", "parent": "ground", "child": "forearm", "location_in_parent_m": [0, 0, 0],
                "coordinate": "elbow_flexion", "range_rad": [0.0, 2.5]}],)";
  auto muscle = [](const std::string& name, const std::string& path) {
    return R"({"name": ")" + name + R"(", "max_isometric_force_N": 800, "optimal_fiber_length_m": 0.12, "tendon_slack_length_m": 0.2, )" + path + "}";
  };
  auto load = [&](const std::string& muscles) {
    return std::make_shared<const fp::MusculoskeletalModel>(
        fp::parse_model_json("{\"name\": \"m\", " + body + "\"muscles\": [" + muscles + "]}", "test"));
  };
  auto what = [](const std::shared_ptr<const fp::MusculoskeletalModel>& model) -> std::string {
    try {
      const fpl::FlatOutputMap flat(model);
    } catch (const fpl::FlatnessError& e) {
      return e.what();
    }
    return "accepted";
  };
  const std::string flexor = R"("length_at_zero_angles_m": 0.4, "moment_arms_m": {"elbow": 0.03})";
  // Two flexors: no positive tendon forces balance, at any posture.
  const std::string two_flexors = what(load(muscle("a", flexor) + ", " + muscle("b", flexor)));
  EXPECT_NE(two_flexors.find("every muscle crossing joint 'elbow' pulls the same way"), std::string::npos) << two_flexors;
  // One muscle for one joint: nothing to choose.
  EXPECT_NE(what(load(muscle("a", flexor))).find("flat outputs need more muscles than joints"), std::string::npos);
  // An extensor whose moment arm -0.02 + 2 c q changes sign at 85.94 deg: from there on it flexes
  // too, and the error names a posture beyond it.
  const double c = 0.02 / 3.0;
  const std::string turning = what(load(muscle("a", flexor) + ", " +
                                        muscle("b", R"("path": {"coordinates": ["elbow_flexion"], "order": 2, "coefficients": [0.25, 0.02, )" +
                                                        std::to_string(-c) + "]}")));
  const std::size_t at = turning.find("pulls the same way at elbow = ");
  ASSERT_NE(at, std::string::npos) << turning;
  EXPECT_GT(std::stod(turning.substr(at + 30)), 85.9);
}
