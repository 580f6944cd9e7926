// The model loader: the arm file loads to the paper's arm numbers, and every kind of bad file
// is rejected with a message naming the field, before anything is built.
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "arm_fixture.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/model/model_description.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace fp = flatsos::plugin;
using nlohmann::json;

namespace {
json arm_json() {
  std::ifstream in(flatsos::test::arm_model_path());
  return json::parse(in);
}

struct BadModel {
  const char* what;
  std::function<void(json&)> spoil;
  std::vector<std::string> message_contains;
};
}  // namespace

TEST(ModelFile, ArmLoadsWithItsMomentArmsAndFlatOutputs) {
  const auto m = fp::load_model_file(flatsos::test::arm_model_path());
  ASSERT_EQ(m.numJoints(), 2);
  ASSERT_EQ(m.numMuscles(), 6);
  Eigen::MatrixXd a_expected(2, 6);
  a_expected << 0.05, -0.05, 0.03, -0.03, 0, 0,  //
      0, 0, 0.03, -0.03, -0.03, 0.03;
  EXPECT_EQ(m.momentArmMatrix(), a_expected);
  Eigen::MatrixXd e_expected(4, 6);
  e_expected << 0.5, 0.5, 0, 0, 0, 0,  //
      0, 0, 0.5, 0.5, 0, 0,            //
      0, 0, 0, 0, 0.5, 0.5,            //
      0, 0, 0, 0, 1, 0;
  EXPECT_EQ(m.flatOutputMatrix(), e_expected);
  EXPECT_EQ(m.muscles[5].parameters.name, "brachialis");
  EXPECT_DOUBLE_EQ(m.muscles[5].parameters.tendon_slack_length_m, 0.0175);
  EXPECT_DOUBLE_EQ(m.muscles[5].parameters.activation_floor, 1e-4);
  EXPECT_DOUBLE_EQ(m.muscles[2].length_at_zero_angles_m, 0.4283);
  EXPECT_EQ(m.jointIndex("elbow"), 1);
  EXPECT_EQ(m.muscleIndex("nope"), -1);
}

TEST(ModelFile, ScenariosAreReadInDegreesAndKeptInRadians) {
  const auto d = fp::load_model_file(flatsos::test::arm_model_path());
  const fp::ScenarioDescription* ol = d.scenario("open_loop");
  ASSERT_NE(ol, nullptr);
  EXPECT_NEAR(ol->q0_rad[1], flatsos::test::deg(10), 1e-15);
  EXPECT_NEAR(ol->qd0_rad_per_s[0], 0.001, 1e-15);  // the paper's 0.001 rad/s, written in deg/s
  EXPECT_NEAR(ol->target_q_rad[0], flatsos::test::deg(90), 1e-15);
  EXPECT_EQ(ol->activations, flatsos::test::paper_a0());
  EXPECT_EQ(ol->duration_s, 3.0);
  EXPECT_EQ(ol->reserves_N.size(), 1);
  const fp::ScenarioDescription* rh = d.scenario("receding_horizon");
  ASSERT_NE(rh, nullptr);
  EXPECT_EQ(rh->activations.size(), 0);  // not given: starts at rest
  EXPECT_EQ(d.scenario("walking"), nullptr);
}

// Muscle j's constant moment arms replaced by a polynomial path over (shoulder, elbow).
static void as_path(json& j, int muscle, int order, const std::vector<double>& coefficients) {
  json& m = j["muscles"][muscle];
  m.erase("length_at_zero_angles_m");
  m.erase("moment_arms_m");
  m["path"] = {{"coordinates", {"shoulder", "elbow"}}, {"order", order}, {"coefficients", coefficients}};
}

TEST(ModelFile, EveryBadFileIsRejectedWithTheFieldNamed) {
  const std::vector<BadModel> cases = {
      {"missing bodies", [](json& j) { j.erase("bodies"); }, {"bodies", "missing"}},
      {"empty muscles", [](json& j) { j["muscles"] = json::array(); }, {"muscles", "empty"}},
      {"negative mass", [](json& j) { j["bodies"][1]["mass_kg"] = -1.76; }, {"bodies[1].mass_kg", "> 0"}},
      {"unphysical products of inertia",
       [](json& j) { j["bodies"][1]["inertia_about_mass_center_kg_m2"] = {0.04, 0.04, 0.04, 0.03, 0.0, 0.0}; },
       {"bodies[1].inertia_about_mass_center_kg_m2", "products of inertia"}},
      {"mass as string", [](json& j) { j["bodies"][0]["mass_kg"] = "2.24"; }, {"bodies[0].mass_kg", "number"}},
      {"com wrong dimension", [](json& j) { j["bodies"][0]["mass_center_m"] = {0.1, 0.0}; },
       {"bodies[0].mass_center_m", "dimension"}},
      {"inertia wrong dimension", [](json& j) { j["bodies"][0]["inertia_about_mass_center_kg_m2"] = {1, 2}; },
       {"inertia_about_mass_center_kg_m2", "dimension"}},
      {"mass centre far out", [](json& j) { j["bodies"][0]["mass_center_m"] = {0.1, -1e38, 0.0}; },
       {"bodies[0].mass_center_m", "within 100 m"}},
      {"mass that swamps the inertia", [](json& j) { j["bodies"][0]["mass_kg"] = 7.8e98; },
       {"bodies[0].mass_kg", "swamps"}},
      {"inertia triangle", [](json& j) { j["bodies"][0]["inertia_about_mass_center_kg_m2"] = {0.01, 0.01, 0.05}; },
       {"inertia_about_mass_center_kg_m2", "triangle"}},
      {"typo key in body", [](json& j) { j["bodies"][0]["mass"] = 2.0; }, {"bodies[0].mass", "unknown key"}},
      {"ground as body name", [](json& j) { j["bodies"][0]["name"] = "ground"; }, {"reserved"}},
      {"duplicate body", [](json& j) { j["bodies"][1]["name"] = "upper_arm"; }, {"duplicate body"}},
      {"unknown joint type", [](json& j) { j["joints"][0]["type"] = "ball"; }, {"joints[0].type", "ball", "slider"}},
      {"unknown parent", [](json& j) { j["joints"][1]["parent"] = "torso"; }, {"joints[1].parent", "torso"}},
      {"unknown child", [](json& j) { j["joints"][1]["child"] = "hand"; }, {"joints[1].child", "hand"}},
      {"children first", [](json& j) { std::swap(j["joints"][0], j["joints"][1]); }, {"joints[0].parent", "not attached"}},
      {"body attached twice", [](json& j) { j["joints"][1]["child"] = "upper_arm"; j["joints"][1]["parent"] = "ground"; },
       {"joints[1].child", "already has a joint"}},
      {"zero axis", [](json& j) { j["joints"][0]["axis"] = {0, 0, 0}; }, {"joints[0].axis", "zero"}},
      {"gravity wrong dimension", [](json& j) { j["gravity_m_per_s2"] = {0, -9.81}; }, {"gravity_m_per_s2", "dimension"}},
      {"unknown top-level key", [](json& j) { j["muscle"] = json::array(); }, {"muscle", "unknown key"}},
      {"unknown muscle model", [](json& j) { j["muscles"][2]["muscle_model"] = "Thelen2003Muscle"; },
       {"muscles[2].muscle_model", "Thelen2003Muscle", "richter_warner", "thelen2003"}},
      {"muscle model not a string", [](json& j) { j["muscle_defaults"]["muscle_model"] = 2003; },
       {"muscle_defaults.muscle_model", "string"}},
      {"missing Fmax", [](json& j) { j["muscles"][0].erase("max_isometric_force_N"); },
       {"muscles[0].max_isometric_force_N", "missing"}},
      {"negative Fmax", [](json& j) { j["muscles"][3]["max_isometric_force_N"] = -1000; },
       {"muscles[3]", "triceps_long", "max_isometric_force_N"}},
      {"gmax <= 1 in defaults", [](json& j) { j["muscle_defaults"]["max_eccentric_force_ratio"] = 0.9; },
       {"muscles[0]", "max_eccentric_force_ratio"}},
      {"typo in defaults", [](json& j) { j["muscle_defaults"]["hill"] = 0.3; }, {"muscle_defaults.hill", "unknown key"}},
      {"Tact > Tdeact", [](json& j) { j["muscles"][2]["activation_time_constant_s"] = 0.1; },
       {"biceps", "activation_time_constant_s"}},
      {"negative l0", [](json& j) { j["muscles"][1]["length_at_zero_angles_m"] = -0.1; },
       {"muscles[1].length_at_zero_angles_m", "> 0"}},
      {"unknown joint in moment arms", [](json& j) { j["muscles"][0]["moment_arms_m"] = {{"wrist", 0.02}}; },
       {"muscles[0].moment_arms_m.wrist", "unknown joint"}},
      {"moment-arm row not N", [](json& j) { j["muscles"][0]["moment_arms_m"] = {0.05, 0.0, 0.01}; },
       {"muscles[0].moment_arms_m", "N x m"}},
      {"scenario angles per joint", [](json& j) { j["scenarios"]["open_loop"]["q0_deg"] = {0.0}; },
       {"scenarios.open_loop.q0_deg", "one value per joint (2), got 1"}},
      {"scenario activation 0", [](json& j) { j["scenarios"]["open_loop"]["activations"][2] = 0.0; },
       {"scenarios.open_loop.activations", "(0, 1]"}},
      {"scenario reserves per muscle", [](json& j) { j["scenarios"]["receding_horizon"]["reserves_N"] = {1.0, 2.0}; },
       {"scenarios.receding_horizon.reserves_N", "one value per muscle"}},
      {"scenario negative reserve", [](json& j) { j["scenarios"]["receding_horizon"]["reserves_N"] = -1.0; },
       {"scenarios.receding_horizon.reserves_N", ">= 0"}},
      {"scenario duration", [](json& j) { j["scenarios"]["open_loop"]["duration_s"] = 0.0; },
       {"scenarios.open_loop.duration_s", "> 0"}},
      {"scenario target as text", [](json& j) { j["scenarios"]["open_loop"]["target_deg"] = "90,0"; },
       {"scenarios.open_loop.target_deg", "array of numbers"}},
      {"scenario unknown key", [](json& j) { j["scenarios"]["open_loop"]["q0_rad"] = {0.0, 0.1}; },
       {"scenarios.open_loop.q0_rad", "unknown key"}},
      {"coordinate path", [](json& j) { j["joints"][1]["coordinate"] = "elbow/flexion"; },
       {"joints[1].coordinate", "without '/'"}},
      {"crosses no joint", [](json& j) { j["muscles"][4]["moment_arms_m"] = {{"elbow", 0.0}}; },
       {"muscles[4].moment_arms_m", "crosses no joint"}},
      {"path and moment arms both",
       [](json& j) { j["muscles"][2]["path"] = {{"coordinates", {"shoulder", "elbow"}}, {"order", 1}, {"coefficients", {0.43, -0.03, -0.03}}}; },
       {"muscles[2]", "not both"}},
      {"path with the wrong coefficient count",
       [](json& j) { as_path(j, 2, 2, {0.43, -0.03, 0.0, -0.03, 0.0}); },
       {"muscles[2].path", "need 6 coefficients, got 5"}},
      {"path order not an integer", [](json& j) { as_path(j, 2, 1, {0.43, -0.03, -0.03}); j["muscles"][2]["path"]["order"] = 1.5; },
       {"muscles[2].path.order", "integer"}},
      {"path over an unknown coordinate",
       [](json& j) { as_path(j, 2, 1, {0.43, -0.03, -0.03}); j["muscles"][2]["path"]["coordinates"][1] = "wrist"; },
       {"muscles[2].path.coordinates[1]", "unknown coordinate 'wrist'"}},
      {"one joint under its name and its coordinate's",
       [](json& j) {
         j["joints"][1]["coordinate"] = "elbow_flexion";
         as_path(j, 2, 1, {0.43, -0.03, -0.03});
         j["muscles"][2]["path"]["coordinates"] = {"elbow", "elbow_flexion"};
       },
       {"muscles[2].path.coordinates", "joint 1 is given twice"}},
      {"held coordinate that is a joint",
       [](json& j) { as_path(j, 2, 1, {0.43, -0.03, -0.03}); j["muscles"][2]["path"]["held_coordinates"] = {{"elbow", 0.1}}; },
       {"muscles[2].path.held_coordinates.elbow", "cannot also be held"}},
      {"held coordinate the path does not use",
       [](json& j) { as_path(j, 2, 1, {0.43, -0.03, -0.03}); j["muscles"][2]["path"]["held_coordinates"] = {{"wrist", 0.1}}; },
       {"muscles[2].path.held_coordinates.wrist", "not one of the path's coordinates"}},
      {"posture-dependent path without a range", [](json& j) { as_path(j, 2, 2, {0.43, -0.03, -0.001, -0.03, 0.0, -0.001}); },
       {"joints[0].range_rad", "required", "biceps"}},
      {"range with lower above upper", [](json& j) { j["joints"][0]["range_rad"] = {1.0, 0.5}; },
       {"joints[0].range_rad", "below upper"}},
      {"range of one number", [](json& j) { j["joints"][0]["range_rad"] = {1.0}; }, {"joints[0].range_rad", "2 numbers"}},
      {"tendon slack inside the range",
       [](json& j) {
         j["joints"][0]["range_rad"] = {0.0, 1.0};
         j["joints"][1]["range_rad"] = {0.0, 2.5};
         as_path(j, 2, 2, {0.43, -0.03, -0.02, -0.03, 0.0, 0.0});
       },
       {"muscles[2].path", "does not exceed the tendon slack length", "shoulder = ", "elbow = ", "would be slack"}},
      {"limit torque without a range",
       [](json& j) { j["joints"][0]["limit_torque"] = {{"stiffness_N_m_per_rad", 100.0}, {"transition_rad", 0.1}}; },
       {"joints[0].range_rad", "required", "limit_torque"}},
      {"limit torque without stiffness",
       [](json& j) {
         j["joints"][0]["range_rad"] = {-1.0, 2.0};
         j["joints"][0]["limit_torque"] = {{"transition_rad", 0.1}};
       },
       {"joints[0].limit_torque.stiffness_N_m_per_rad", "missing"}},
      {"limit torque with a zero transition",
       [](json& j) {
         j["joints"][0]["range_rad"] = {-1.0, 2.0};
         j["joints"][0]["limit_torque"] = {{"stiffness_N_m_per_rad", 100.0}, {"transition_rad", 0.0}};
       },
       {"joints[0].limit_torque.transition_rad", "> 0"}},
      {"limit torque with negative damping",
       [](json& j) {
         j["joints"][1]["range_rad"] = {0.0, 2.5};
         j["joints"][1]["limit_torque"] = {{"stiffness_N_m_per_rad", 100.0}, {"transition_rad", 0.1}, {"damping_N_m_s_per_rad", -1.0}};
       },
       {"joints[1].limit_torque.damping_N_m_s_per_rad", ">= 0"}},
      {"limit torque with an unknown key",
       [](json& j) {
         j["joints"][0]["range_rad"] = {-1.0, 2.0};
         j["joints"][0]["limit_torque"] = {{"stiffness_N_m_per_rad", 100.0}, {"transition_rad", 0.1}, {"stiffness", 5.0}};
       },
       {"joints[0].limit_torque.stiffness", "unknown key"}},
      {"effort weights of an unknown kind", [](json& j) { j["effort_weights"] = "metabolic"; },
       {"effort_weights", "unknown kind 'metabolic'"}},
      {"effort weights without a muscle",
       [](json& j) {
         j["effort_weights"] = json::object();
         for (const auto& m : j["muscles"]) j["effort_weights"][m["name"].get<std::string>()] = 1.0;
         j["effort_weights"].erase("biceps");
       },
       {"effort_weights.biceps", "missing"}},
      {"effort weights of an unknown muscle",
       [](json& j) {
         j["effort_weights"] = json::object();
         for (const auto& m : j["muscles"]) j["effort_weights"][m["name"].get<std::string>()] = 1.0;
         j["effort_weights"]["deltoid"] = 1.0;
       },
       {"effort_weights.deltoid", "unknown key"}},
      {"negative effort weight",
       [](json& j) {
         j["effort_weights"] = json::object();
         for (const auto& m : j["muscles"]) j["effort_weights"][m["name"].get<std::string>()] = 1.0;
         j["effort_weights"]["biceps"] = -1.0;
       },
       {"effort_weights.biceps", ">= 0"}},
      {"effort weights all zero",
       [](json& j) {
         j["effort_weights"] = json::object();
         for (const auto& m : j["muscles"]) j["effort_weights"][m["name"].get<std::string>()] = 0.0;
       },
       {"effort_weights", "nothing to minimize"}},
      {"pennation of 90 degrees", [](json& j) { j["muscles"][1]["pennation_angle_at_optimal_rad"] = 1.6; },
       {"muscles[1]", "pennation_angle_at_optimal_rad"}},
      {"negative passive strain", [](json& j) { j["muscle_defaults"]["passive_fiber_strain_at_one_norm_force"] = -0.1; },
       {"muscles[0]", "passive_fiber_strain_at_one_norm_force"}},
      {"duplicate muscle", [](json& j) { j["muscles"][1]["name"] = "anterior_deltoid"; }, {"duplicate muscle"}},
      {"E wrong shape", [](json& j) { j["flat_outputs"].erase(3); }, {"flat_outputs", "m - N = 4 rows"}},
      {"E unknown muscle", [](json& j) { j["flat_outputs"][0]["weights"]["deltoid"] = 1.0; },
       {"flat_outputs[0].weights.deltoid", "unknown muscle"}},
      {"E weight not a number", [](json& j) { j["flat_outputs"][1]["weights"]["biceps"] = nullptr; },
       {"flat_outputs[1].weights.biceps", "number"}},
  };
  for (const auto& c : cases) {
    json j = arm_json();
    c.spoil(j);
    try {
      fp::parse_model_json(j.dump(), "case.json");
      ADD_FAILURE() << "accepted: " << c.what;
    } catch (const fp::ModelFileError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("case.json"), std::string::npos) << c.what << ": " << msg;
      for (const auto& part : c.message_contains)
        EXPECT_NE(msg.find(part), std::string::npos) << c.what << ": '" << part << "' not in: " << msg;
    }
  }
}

TEST(ModelFile, MalformedJsonAndMissingFileAreRejected) {
  EXPECT_THROW(fp::parse_model_json("{\"bodies\": [", "broken.json"), fp::ModelFileError);
  // A number beyond double's range is a JSON error too (found by the fuzzer: it escaped as
  // nlohmann's out_of_range).
  EXPECT_THROW(fp::parse_model_json("{\"gravity_m_per_s2\": [0, -1e400, 0]}", "huge.json"), fp::ModelFileError);
  try {
    fp::parse_model_json("{\"bodies\": [", "broken.json");
  } catch (const fp::ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find("not valid JSON"), std::string::npos);
  }
  try {
    fp::load_model_file("/nonexistent/arm.json");
    ADD_FAILURE();
  } catch (const fp::ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot be opened"), std::string::npos);
  }
}

TEST(ModelFile, BuildingAModelValidatesACodeBuiltDescriptionToo) {
  auto d = fp::load_model_file(flatsos::test::arm_model_path());
  d.muscles[0].moment_arms_m.resize(3);
  EXPECT_THROW(fp::MusculoskeletalModel{d}, fp::ModelFileError);
}

TEST(ModelFile, ThreeLinkChainFromAFileBuildsAndHasTheRightMassMatrixSize) {
  json j = arm_json();
  j["bodies"].push_back({{"name", "hand"}, {"mass_kg", 0.5}, {"mass_center_m", {0.05, 0, 0}},
                         {"inertia_about_mass_center_kg_m2", 0.001}});
  j["joints"].push_back({{"name", "wrist"}, {"type", "pin"}, {"parent", "forearm"}, {"child", "hand"},
                         {"location_in_parent_m", {0.32, 0, 0}}});
  j["muscles"].push_back({{"name", "flexor"}, {"max_isometric_force_N", 200}, {"optimal_fiber_length_m", 0.06},
                          {"tendon_slack_length_m", 0.2}, {"length_at_zero_angles_m", 0.26},
                          {"moment_arms_m", {{"wrist", 0.01}}}});
  // m - N = 7 - 3 = 4: the arm's four flat outputs still have the right shape; its scenarios do not.
  j.erase("scenarios");
  fp::MusculoskeletalModel model(fp::parse_model_json(j.dump(), "three_link.json"));
  EXPECT_EQ(model.numJoints(), 3);
  EXPECT_EQ(model.massMatrix(Eigen::Vector3d(0.1, 0.2, 0.3)).rows(), 3);
  EXPECT_EQ(model.momentArmMatrix()(2, 6), 0.01);
}

TEST(ModelFile, EffortWeightsAndJointLimitsAreRead) {
  json j = arm_json();
  EXPECT_EQ(fp::parse_model_json(j.dump(), "a.json").effort_weights.kind, fp::EffortWeights::Kind::Default);
  j["effort_weights"] = "normalized_tendon_force";
  EXPECT_EQ(fp::parse_model_json(j.dump(), "a.json").effort_weights.kind, fp::EffortWeights::Kind::NormalizedTendonForce);
  j["effort_weights"] = json::object();
  double w = 1.0;
  for (const auto& m : j["muscles"]) j["effort_weights"][m["name"].get<std::string>()] = w++;
  j["joints"][1]["range_rad"] = {0.0, 2.5};
  j["joints"][1]["limit_torque"] = {{"stiffness_N_m_per_rad", 300.0}, {"transition_rad", 0.1}};
  const fp::ModelDescription d = fp::parse_model_json(j.dump(), "a.json");
  ASSERT_EQ(d.effort_weights.kind, fp::EffortWeights::Kind::PerMuscle);
  for (int k = 0; k < d.numMuscles(); ++k) EXPECT_EQ(d.effort_weights.per_muscle[k], k + 1.0);
  EXPECT_EQ(d.joints[1].limit.stiffness_N_m_per_rad, 300.0);
  EXPECT_EQ(d.joints[1].limit.transition_rad, 0.1);
  EXPECT_EQ(d.joints[1].limit.damping_N_m_s_per_rad, 0.0);
  EXPECT_FALSE(d.joints[0].limit.enabled());
}

TEST(ModelFile, AMuscleModelIsChosenPerMuscleStartsFromItsDefaultsAndRoundTrips) {
  json j = arm_json();
  j["muscles"][1]["muscle_model"] = "thelen2003";
  j["muscles"][1]["activation_time_constant_s"] = 0.02;  // the muscle's own field wins
  const fp::ModelDescription d = fp::parse_model_json(j.dump(), "arm with one Thelen muscle");
  const flatsos::muscles::MuscleParameters& thelen = d.muscles[1].parameters;
  EXPECT_EQ(thelen.model->name(), "thelen2003");
  EXPECT_DOUBLE_EQ(thelen.activation_time_constant_s, 0.02);
  EXPECT_DOUBLE_EQ(thelen.deactivation_time_constant_s, 0.05);  // OpenSim's default, not the file's
  EXPECT_DOUBLE_EQ(thelen.max_eccentric_force_ratio, 1.4);
  EXPECT_EQ(d.muscles[0].parameters.model->name(), "richter_warner");

  // Written and read again: the same model and fields, also where a field equals the other
  // model's default.
  fp::ModelDescription changed = d;
  changed.muscles[1].parameters.hill_constant = 0.3;
  changed.muscles[1].parameters.deactivation_time_constant_s = 0.04;  // Richter & Warner's default
  const fp::ModelDescription again = fp::parse_model_json(fp::model_json_text(changed), "round trip");
  const flatsos::muscles::MuscleParameters& back = again.muscles[1].parameters;
  EXPECT_EQ(back.model->name(), "thelen2003");
  EXPECT_DOUBLE_EQ(back.hill_constant, 0.3);
  EXPECT_DOUBLE_EQ(back.deactivation_time_constant_s, 0.04);
  EXPECT_DOUBLE_EQ(back.max_eccentric_force_ratio, 1.4);
  EXPECT_EQ(again.muscles[0].parameters.model->name(), "richter_warner");
  EXPECT_NO_THROW(fp::MusculoskeletalModel{again});
}

TEST(ModelFile, DeGrooteFreglysSmoothingIsReadAndWritten) {
  json j = arm_json();
  j["muscle_defaults"]["muscle_model"] = "degroote_fregly2016";
  // The file's own width (Richter & Warner's W = 0.56) overrides the model's scale 1 and is
  // refused: De Groote's curve can only be widened.
  EXPECT_THROW(fp::parse_model_json(j.dump(), "narrow"), std::exception);
  j["muscle_defaults"].erase("force_length_width");
  j["muscles"][0]["activation_dynamics_smoothing"] = 10.0;
  const fp::ModelDescription d = fp::parse_model_json(j.dump(), "arm of De Groote-Fregly muscles");
  EXPECT_EQ(d.muscles[1].parameters.model->name(), "degroote_fregly2016");
  EXPECT_DOUBLE_EQ(d.muscles[1].parameters.activation_dynamics_smoothing, 0.1);  // OpenSim's default
  EXPECT_DOUBLE_EQ(d.muscles[0].parameters.activation_dynamics_smoothing, 10.0);
  const fp::ModelDescription again = fp::parse_model_json(fp::model_json_text(d), "round trip");
  EXPECT_DOUBLE_EQ(again.muscles[0].parameters.activation_dynamics_smoothing, 10.0);
  EXPECT_EQ(again.muscles[1].parameters.model->name(), "degroote_fregly2016");
  j["muscles"][0]["activation_dynamics_smoothing"] = 0.0;
  EXPECT_THROW(fp::parse_model_json(j.dump(), "zero smoothing"), std::exception);
}
