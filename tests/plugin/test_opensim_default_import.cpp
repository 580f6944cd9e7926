// An .osim file given where a model is expected: imported with OpenSim's own settings (every
// joint's one free coordinate kept, paths fitted to the geometry, ranges narrowed to where the
// tendons can be taut and each coordinate is pulled both ways), and the narrowing checked
// against what the geometry says by hand.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"

#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"

namespace {

using namespace flatsos::plugin;

const std::string kModels = std::string(FLATSOS_SOURCE_DIR) + "/models/opensim/";
constexpr double kPi = 3.14159265358979323846;

// Tug_of_War_Millard: a block on a slider (OpenSim's range +-0.3 m) between two muscles whose
// paths are straight, L = 0.3 m -+ x, with tendon slack length 0.2 m and optimal fibre 0.1 m
// (no pennation): a tendon is taut with a tenth of the optimal fibre to spare for |x| < 0.09 m.
TEST(OpenSimDefaultImport, TheTugOfWarsSliderIsNarrowedToWhereBothTendonsAreTaut) {
  const OpenSimImport imported = import_opensim_file(kModels + "Tug_of_War_Millard.osim");
  const ModelDescription& model = imported.model;
  ASSERT_EQ(model.numJoints(), 1);
  EXPECT_EQ(model.joints[0].type, JointType::Slider);
  EXPECT_EQ(model.numMuscles(), 2);
  const auto& range = model.joints[0].range_rad;
  const double grid_step_m = 0.6 / 100;  // the narrowing's grid over OpenSim's range
  EXPECT_LE(range[1], 0.09 + 1e-12);  // at 0.09 the spare fibre is exactly the tenth, up to rounding
  EXPECT_GE(range[1], 0.09 - grid_step_m);
  EXPECT_GE(range[0], -0.09 - 1e-12);
  EXPECT_LE(range[0], -0.09 + grid_step_m);
  const auto provenance = nlohmann::json::parse(model.provenance_json);
  bool noted = false;
  for (const auto& note : provenance["notes"]) noted |= note.get<std::string>().rfind("range of block_tz narrowed", 0) == 0;
  EXPECT_TRUE(noted) << provenance["notes"].dump();
}

// arm26: both coordinates kept; the elbow keeps OpenSim's range, the shoulder loses the
// elevations where every muscle crossing it pulls one way (beyond about 80 deg) but keeps the
// arm's working range.
TEST(OpenSimDefaultImport, Arm26KeepsBothCoordinatesAndTheShouldersWorkingRange) {
  const ModelDescription model = load_model_file(kModels + "arm26/arm26.osim");
  ASSERT_EQ(model.numJoints(), 2);
  EXPECT_EQ(model.numMuscles(), 6);
  const JointDescription& shoulder = model.joints[static_cast<std::size_t>(model.jointIndex("r_shoulder"))];
  const JointDescription& elbow = model.joints[static_cast<std::size_t>(model.jointIndex("r_elbow"))];
  EXPECT_NEAR(elbow.range_rad[0], 0.0, 1e-12);
  EXPECT_NEAR(elbow.range_rad[1], 2.26892803, 1e-12);  // the file's 130 deg
  EXPECT_LT(shoulder.range_rad[0], -30 * kPi / 180);
  EXPECT_GT(shoulder.range_rad[1], 60 * kPi / 180);
  EXPECT_LT(shoulder.range_rad[1], 120 * kPi / 180);
}

TEST(OpenSimDefaultImport, OnlyAPathEndingInOsimIsImported) {
  EXPECT_TRUE(is_opensim_model_file("a/b/arm26.osim"));
  EXPECT_TRUE(is_opensim_model_file("ARM26.OSIM"));
  EXPECT_FALSE(is_opensim_model_file("arm26.osim.json"));
  EXPECT_FALSE(is_opensim_model_file("osim"));
  try {
    load_model_file(kModels + "no_such_model.osim");
    FAIL() << "a missing .osim was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_model.osim"), std::string::npos) << e.what();
  }
}

}  // namespace
