// Slider (prismatic) joints outside the dynamics (test_pin_tree_dynamics.cpp has those): model
// files (round trip, every field of the wrong type named), a cart on a tilted rail with a pole,
// built in Simbody and simulated; and the OpenSim importer on a small OpenSim model written here
// (a SliderJoint and a CustomJoint translation, positions computed by hand, refusals named) and
// on OpenSim's Tug_of_War_Millard (a block on a SliderJoint between two muscles).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <functional>
#include <sstream>
#include <string>

#include "arm_fixture.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"
#include "flatsos/plugin/io/opensim_kinematics.hpp"
#include "flatsos/plugin/io/opensim_model.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"
#include "flatsos/plugin/model/plausibility.hpp"
#include "flatsos/plugin/model/posture_grid.hpp"
#include "flatsos/plugin/model/static_equilibrium.hpp"

namespace fp = flatsos::plugin;
using nlohmann::json;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A cart on a rail tilted up by atan(0.2) with a pole hinged on it; two muscles pull the cart
// each way (1 m of muscle per m of rail), two swing the pole.
json cart_json() {
  auto muscle = [](const char* name, double l0, double slack, const char* joint, double arm) {
    return json{{"name", name},
                {"max_isometric_force_N", 500.0},
                {"optimal_fiber_length_m", 0.1},
                {"tendon_slack_length_m", slack},
                {"length_at_zero_angles_m", l0},
                {"moment_arms_m", {{joint, arm}}}};
  };
  return json{
      {"name", "cart_and_pole"},
      {"gravity_m_per_s2", {0.0, -9.81, 0.0}},
      {"bodies",
       {{{"name", "cart"}, {"mass_kg", 5.0}, {"mass_center_m", {0.0, 0.0, 0.0}}, {"inertia_about_mass_center_kg_m2", {0.1, 0.1, 0.1}}},
        {{"name", "pole"}, {"mass_kg", 1.0}, {"mass_center_m", {0.0, -0.3, 0.0}}, {"inertia_about_mass_center_kg_m2", 0.01}}}},
      {"joints",
       {{{"name", "rail"},
         {"type", "slider"},
         {"parent", "ground"},
         {"child", "cart"},
         {"location_in_parent_m", {0.0, 0.5, 0.0}},
         {"axis", {1.0, 0.2, 0.0}},
         {"range_m", {-0.05, 0.05}},
         {"limit_force", {{"stiffness_N_per_m", 5000.0}, {"transition_m", 0.01}, {"damping_N_s_per_m", 20.0}}}},
        {{"name", "hinge"},
         {"type", "pin"},
         {"parent", "cart"},
         {"child", "pole"},
         {"location_in_parent_m", {0.0, 0.0, 0.0}},
         {"range_rad", {-1.0, 1.0}}}}},
      {"muscles",
       {muscle("pull_right", 0.16, 0.05, "rail", -1.0), muscle("pull_left", 0.16, 0.05, "rail", 1.0),
        muscle("swing_fwd", 0.3, 0.2, "hinge", 0.03), muscle("swing_back", 0.3, 0.2, "hinge", -0.03)}},
      {"scenarios", {{"open_loop", {{"q0_deg", {0.02, 20.0}}, {"qd0_deg_per_s", {0.5, 0.0}}, {"target_deg", {-0.01, 0.0}}}}}}};
}

std::string load_error(const json& j) {
  try {
    fp::parse_model_json(j.dump(), "cart.json");
  } catch (const fp::ModelFileError& e) {
    return e.what();
  }
  return "accepted";
}

std::string validation_error(const fp::ModelDescription& d) {
  try {
    fp::validate(d, "cart");
  } catch (const fp::ModelFileError& e) {
    return e.what();
  }
  return "accepted";
}

}  // namespace

TEST(SliderModelFile, ASliderRoundTripsWithItsRangeLimitAndScenarioInMetres) {
  const fp::ModelDescription d = fp::parse_model_json(cart_json().dump(), "cart.json");
  const fp::JointDescription& rail = d.joints[0];
  ASSERT_TRUE(rail.isSlider());
  EXPECT_FALSE(d.joints[1].isSlider());
  EXPECT_LT((rail.axis - Eigen::Vector3d(1.0, 0.2, 0.0) / std::sqrt(1.04)).norm(), 1e-15);
  EXPECT_EQ(rail.range_rad[0], -0.05);
  EXPECT_EQ(rail.range_rad[1], 0.05);
  EXPECT_EQ(rail.limit.stiffness_N_m_per_rad, 5000.0);  // N/m for a slider
  EXPECT_EQ(rail.limit.transition_rad, 0.01);
  EXPECT_EQ(rail.limit.damping_N_m_s_per_rad, 20.0);
  // Scenario entries: the slider's in m and m/s as written, the pin's from degrees.
  const fp::ScenarioDescription& sc = *d.scenario("open_loop");
  EXPECT_EQ(sc.q0_rad[0], 0.02);
  EXPECT_NEAR(sc.q0_rad[1], 20.0 * kPi / 180.0, 1e-15);
  EXPECT_EQ(sc.qd0_rad_per_s[0], 0.5);
  EXPECT_EQ(sc.target_q_rad[0], -0.01);

  const std::string text = fp::model_json_text(d);
  const fp::ModelDescription back = fp::parse_model_json(text, "round trip");
  EXPECT_EQ(fp::model_json_text(back), text);
  EXPECT_TRUE(back.joints[0].isSlider());
  EXPECT_EQ(back.joints[0].axis, rail.axis);
  EXPECT_EQ(back.joints[0].range_rad, rail.range_rad);
  EXPECT_EQ(back.scenario("open_loop")->q0_rad, sc.q0_rad);
  const json written = json::parse(text);
  EXPECT_EQ(written["joints"][0]["type"], "slider");
  EXPECT_TRUE(written["joints"][0].contains("range_m"));
  EXPECT_TRUE(written["joints"][0]["limit_force"].contains("stiffness_N_per_m"));
  EXPECT_FALSE(written["joints"][0].contains("range_rad"));
  EXPECT_EQ(written["joints"][1]["type"], "pin");
  EXPECT_TRUE(written["joints"][1].contains("range_rad"));
  EXPECT_EQ(written["scenarios"]["open_loop"]["q0_deg"][0], 0.02);  // metres, not converted
  EXPECT_NEAR(written["scenarios"]["open_loop"]["q0_deg"][1].get<double>(), 20.0, 1e-12);

  EXPECT_EQ(fp::describe_posture(d, Eigen::Vector2d(0.1, kPi / 2)), "rail = 0.100000 m, hinge = 90.000000 deg");
  EXPECT_TRUE(fp::plausibility_warnings(d).empty());  // 1 m of muscle per m of rail is plausible
  EXPECT_TRUE(fp::joint_angle_warnings(d, Eigen::Vector2d(2.9, 6.0), "q").empty());
  const auto far = fp::joint_angle_warnings(d, Eigen::Vector2d(300.0, 0.0), "q");  // 300 m: cm given as m?
  ASSERT_EQ(far.size(), 1u);
  EXPECT_NE(far[0].find("q.rail: 300 m"), std::string::npos) << far[0];
}

TEST(SliderModelFile, AFieldOfTheOtherTypeOrAMissingAxisIsRefusedNamingTheField) {
  struct Case {
    const char* what;
    std::function<void(json&)> spoil;
    std::vector<std::string> words;
  };
  const std::vector<Case> cases = {
      {"slider range in rad", [](json& j) { j["joints"][0]["range_rad"] = j["joints"][0]["range_m"]; j["joints"][0].erase("range_m"); },
       {"joints[0].range_rad", "range_m", "slider"}},
      {"pin range in m", [](json& j) { j["joints"][1]["range_m"] = {-1.0, 1.0}; }, {"joints[1].range_m", "range_rad", "pin"}},
      {"slider limit torque", [](json& j) { j["joints"][0]["limit_torque"] = j["joints"][0]["limit_force"]; j["joints"][0].erase("limit_force"); },
       {"joints[0].limit_torque", "limit_force"}},
      {"pin limit force", [](json& j) { j["joints"][1]["limit_force"] = {{"stiffness_N_per_m", 1.0}, {"transition_m", 0.1}}; },
       {"joints[1].limit_force", "limit_torque"}},
      {"slider without axis", [](json& j) { j["joints"][0].erase("axis"); }, {"joints[0].axis", "required"}},
      {"slider limit in torque units",
       [](json& j) { j["joints"][0]["limit_force"] = {{"stiffness_N_m_per_rad", 1.0}, {"transition_m", 0.1}}; },
       {"joints[0].limit_force.stiffness_N_per_m", "missing"}},
      {"slider limit without range", [](json& j) { j["joints"][0].erase("range_m"); }, {"joints[0].range_m", "required", "limit_force"}},
      {"slider range reversed", [](json& j) { j["joints"][0]["range_m"] = {0.05, -0.05}; }, {"joints[0].range_m", "below"}},
      {"slider zero axis", [](json& j) { j["joints"][0]["axis"] = {0.0, 0.0, 0.0}; }, {"joints[0].axis", "zero"}},
      {"unknown type", [](json& j) { j["joints"][0]["type"] = "prismatic"; }, {"joints[0].type", "prismatic", "slider"}},
      {"slack tendon along the rail", [](json& j) { j["muscles"][0]["length_at_zero_angles_m"] = 0.09; },
       {"muscles[0]", "rail = -0.050000 m", "slack"}},
  };
  for (const auto& c : cases) {
    json j = cart_json();
    c.spoil(j);
    const std::string e = load_error(j);
    for (const auto& w : c.words) EXPECT_NE(e.find(w), std::string::npos) << c.what << ": '" << w << "' not in: " << e;
  }
  // Built in code: validation names the slider's own fields.
  const fp::ModelDescription good = fp::parse_model_json(cart_json().dump(), "cart.json");
  fp::ModelDescription d = good;
  d.joints[0].range_rad = {0.05, -0.05};
  EXPECT_NE(validation_error(d).find("joints[0].range_m"), std::string::npos) << validation_error(d);
  d = good;
  d.joints[0].limit.stiffness_N_m_per_rad = -1.0;
  EXPECT_NE(validation_error(d).find("joints[0].limit_force.stiffness_N_per_m"), std::string::npos) << validation_error(d);
  d = good;
  d.joints[0].limit.transition_rad = 0.0;
  EXPECT_NE(validation_error(d).find("joints[0].limit_force.transition_m"), std::string::npos) << validation_error(d);
  d = good;
  d.joints[0].axis = Eigen::Vector3d(0.0, std::nan(""), 0.0);
  EXPECT_NE(validation_error(d).find("joints[0].axis"), std::string::npos) << validation_error(d);
  d = good;
  d.joints[1].limit.stiffness_N_m_per_rad = 100.0;
  d.joints[1].limit.transition_rad = -1.0;  // a pin keeps its own names
  EXPECT_NE(validation_error(d).find("joints[1].limit_torque.transition_rad"), std::string::npos) << validation_error(d);
}

TEST(SliderModel, TheRailsLimitForceActsBeyondItsRangeInNewtons) {
  const fp::MusculoskeletalModel model(fp::parse_model_json(cart_json().dump(), "cart.json"));
  Eigen::Vector2d limit;
  // 2 cm beyond the upper end (past the 1 cm transition), at rest: the spring alone, -k x.
  model.pinTree().jointLimitTorques(Eigen::Vector2d(0.07, 0.0), Eigen::Vector2d::Zero(), limit);
  EXPECT_NEAR(limit[0], -5000.0 * 0.02, 1e-9);
  // Moving outwards at 0.1 m/s adds the damper, -c qd; below the lower end it pushes up.
  model.pinTree().jointLimitTorques(Eigen::Vector2d(0.07, 0.0), Eigen::Vector2d(0.1, 0.0), limit);
  EXPECT_NEAR(limit[0], -5000.0 * 0.02 - 20.0 * 0.1, 1e-9);
  model.pinTree().jointLimitTorques(Eigen::Vector2d(-0.08, 0.0), Eigen::Vector2d::Zero(), limit);
  EXPECT_NEAR(limit[0], 5000.0 * 0.03, 1e-9);
  model.pinTree().jointLimitTorques(Eigen::Vector2d(0.04, 0.0), Eigen::Vector2d(0.1, 0.0), limit);
  EXPECT_EQ(limit[0], 0.0);
  // Inverse dynamics subtracts it: the muscles need that much less.
  Eigen::Vector2d tau, rigid;
  fp::ModelWorkspace ws = model.makeWorkspace();
  model.inverseDynamics(ws, Eigen::Vector2d(0.07, 0.0), Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), tau);
  model.rigidBodyInverseDynamics(ws, Eigen::Vector2d(0.07, 0.0), Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), rigid);
  EXPECT_NEAR(tau[0], rigid[0] + 5000.0 * 0.02, 1e-9);
}

TEST(SliderModel, TheCartAndPoleSimulateInSimbodyAndTheRailCarriesTheirWeight) {
  const fp::MusculoskeletalModel model(fp::parse_model_json(cart_json().dump(), "cart.json"));
  // The pole hanging still while the cart accelerates along the rail: both move as one body,
  // F = (m_cart + m_pole) (qdd + g sin theta).
  const double theta = std::atan(0.2), g = 9.81, qdd = 1.7;
  const Eigen::VectorXd tau = model.inverseDynamics(Eigen::Vector2d(0.05, 0.0), Eigen::Vector2d::Zero(), Eigen::Vector2d(qdd, 0.0));
  EXPECT_NEAR(tau[0], 6.0 * (qdd + g * std::sin(theta)), 1e-12);
  // The pole's mass centre 0.3 m below the hinge accelerates with the cart (a along the rail and
  // gravity): the hinge's torque about z is r x m (a - g) with r = (0, -0.3, 0).
  const Eigen::Vector3d a(qdd * std::cos(theta), qdd * std::sin(theta) + g, 0.0), r(0.0, -0.3, 0.0);
  EXPECT_NEAR(tau[1], r.cross(1.0 * a)[2], 1e-12);

  SimTK::State s = model.defaultState();
  model.setJointAngles(s, Eigen::Vector2d(0.0, 0.2));
  fp::equilibrate_tendons(model, s, Eigen::VectorXd::Constant(4, 0.1));
  model.setExcitations(s, Eigen::VectorXd::Constant(4, 0.1));
  fp::SimulationOptions options;
  options.duration_s = 0.2;
  const fp::SimulationResult result = fp::simulate(model, s, options);
  ASSERT_TRUE(result.completed()) << result.message;
  const Eigen::VectorXd q = model.jointAngles(result.final_state);
  EXPECT_TRUE(q.allFinite());
  EXPECT_GT(std::abs(q[0]), 1e-4);  // the cart moved along its rail
  // The cart's frame stayed parallel to ground (a slider does not turn it).
  model.system().realize(result.final_state, SimTK::Stage::Position);
  const SimTK::Mat33 R = model.joint(0).getBodyTransform(result.final_state).R().asMat33();
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) EXPECT_NEAR(R[row][col], row == col ? 1.0 : 0.0, 1e-15);
}

// ---- The OpenSim importer ---------------------------------------------------------------------
// A cart on a rail (ground frame at (0.1, 0.9, 0) turned 0.3 rad about z, so the SliderJoint's x
// slides along (cos 0.3, sin 0.3, 0); the cart's joint frame 5 cm below its origin) with a pole
// on a PinJoint 10 cm along the cart's x; two muscles pull the cart, one swings the pole.

namespace {

const double kTurn = 0.3;  // the rail's parent frame about z
Eigen::Matrix3d turned() { return Eigen::AngleAxisd(kTurn, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

std::string frame(const std::string& name, const std::string& parent, const std::string& translation,
                  const std::string& orientation = "0 0 0") {
  return "<PhysicalOffsetFrame name=\"" + name + "\"><socket_parent>" + parent + "</socket_parent><translation>" + translation +
         "</translation><orientation>" + orientation + "</orientation></PhysicalOffsetFrame>";
}
std::string osim_coordinate(const std::string& name, const std::string& range) {
  return "<Coordinate name=\"" + name + "\"><default_value>0</default_value><range>" + range + "</range></Coordinate>";
}
std::string osim_muscle(const std::string& name, const std::string& from, const std::string& to) {
  auto point = [&](const std::string& frame_path, int k) {
    return "<PathPoint name=\"" + name + std::to_string(k) + "\"><socket_parent_frame>" + frame_path +
           "</socket_parent_frame><location>0 0 0</location></PathPoint>";
  };
  return "<Millard2012EquilibriumMuscle name=\"" + name + "\"><GeometryPath name=\"path\"><PathPointSet><objects>" +
         point(from, 1) + point(to, 2) +
         "</objects></PathPointSet></GeometryPath><max_isometric_force>800</max_isometric_force>"
         "<optimal_fiber_length>0.1</optimal_fiber_length><tendon_slack_length>0.2</tendon_slack_length>"
         "</Millard2012EquilibriumMuscle>";
}

const std::string kSliderRail = "<SliderJoint name=\"rail\"><socket_parent_frame>ground_offset</socket_parent_frame>"
                                "<socket_child_frame>cart_offset</socket_child_frame><coordinates>" +
                                osim_coordinate("rail_x", "-0.2 0.2") + "</coordinates><frames>" +
                                frame("ground_offset", "/ground", "0.1 0.9 0", "0 0 0.3") +
                                frame("cart_offset", "/bodyset/cart", "0 -0.05 0") + "</frames></SliderJoint>";

// The rail as a CustomJoint whose translation2 (F's y) follows rail_x through `function`.
std::string custom_rail(const std::string& function) {
  auto axis = [](const std::string& name, const std::string& coordinates, const std::string& direction, const std::string& f) {
    return "<TransformAxis name=\"" + name + "\"><coordinates>" + coordinates + "</coordinates><axis>" + direction + "</axis>" + f +
           "</TransformAxis>";
  };
  const std::string zero = "<Constant name=\"function\"><value>0</value></Constant>";
  return "<CustomJoint name=\"rail\"><socket_parent_frame>ground_offset</socket_parent_frame><socket_child_frame>cart_offset"
         "</socket_child_frame><coordinates>" +
         osim_coordinate("rail_x", "-0.2 0.2") + "</coordinates><frames>" + frame("ground_offset", "/ground", "0.1 0.9 0", "0 0 0.3") +
         frame("cart_offset", "/bodyset/cart", "0 -0.05 0") + "</frames><SpatialTransform>" + axis("rotation1", "", "0 0 1", zero) +
         axis("rotation2", "", "1 0 0", zero) + axis("rotation3", "", "0 1 0", zero) + axis("translation1", "", "1 0 0", zero) +
         axis("translation2", "rail_x", "0 1 0", function) + axis("translation3", "", "0 0 1", zero) +
         "</SpatialTransform></CustomJoint>";
}

std::string cart_osim(const std::string& rail = kSliderRail) {
  return "<?xml version=\"1.0\" encoding=\"UTF-8\" ?><OpenSimDocument Version=\"40500\"><Model name=\"cart_rail\">"
         "<gravity>0 -9.80665 0</gravity><BodySet><objects>"
         "<Body name=\"cart\"><mass>4</mass><mass_center>0.02 0 0.01</mass_center><inertia>0.02 0.03 0.04 0.001 0 0</inertia></Body>"
         "<Body name=\"pole\"><mass>1</mass><mass_center>0 -0.3 0</mass_center><inertia>0.01 0.001 0.01 0 0 0</inertia></Body>"
         "</objects></BodySet><JointSet><objects>" +
         rail +
         "<PinJoint name=\"hinge\"><socket_parent_frame>cart_hinge</socket_parent_frame><socket_child_frame>pole_offset"
         "</socket_child_frame><coordinates>" +
         osim_coordinate("pole_angle", "-1 1") + "</coordinates><frames>" + frame("cart_hinge", "/bodyset/cart", "0.1 0 0") +
         frame("pole_offset", "/bodyset/pole", "0 0 0") +
         "</frames></PinJoint></objects></JointSet><ForceSet><objects>" + osim_muscle("pull", "/ground", "/bodyset/cart") +
         osim_muscle("push", "/ground", "/bodyset/cart") + osim_muscle("swing", "/bodyset/cart", "/bodyset/pole") +
         "</objects></ForceSet></Model></OpenSimDocument>";
}

std::vector<fp::OpenSimPolynomialPath> cart_paths() {
  auto fitted = [](const std::string& name, const std::string& coordinate, const std::string& c) {
    return "<FunctionBasedPath name=\"/forceset/" + name + "\"><coordinate_paths>" + coordinate +
           "</coordinate_paths><length_function><MultivariatePolynomialFunction><coefficients>" + c +
           "</coefficients><dimension>1</dimension><order>1</order></MultivariatePolynomialFunction></length_function>"
           "</FunctionBasedPath>";
  };
  // OpenSim's order for one coordinate: 1, q.
  return fp::parse_opensim_function_based_paths("<OpenSimDocument><Set_FunctionBasedPath_><objects>" +
                                                    fitted("pull", "/jointset/rail/rail_x", "0.5 -1.0") +
                                                    fitted("push", "/jointset/rail/rail_x", "0.5 1.0") +
                                                    fitted("swing", "/jointset/hinge/pole_angle", "0.32 -0.02") +
                                                    "</objects></Set_FunctionBasedPath_></OpenSimDocument>",
                                                "cart_paths.xml");
}

fp::OpenSimImportOptions keep_rail_and_pole() {
  fp::OpenSimImportOptions o;
  o.keep = {"rail_x", "pole_angle"};
  return o;
}

std::string cart_import_error(const std::string& osim, const fp::OpenSimImportOptions& o = keep_rail_and_pole()) {
  try {
    fp::import_opensim_model(fp::parse_opensim_model(osim, "cart.osim"), cart_paths(), o);
  } catch (const fp::OpenSimModelError& e) {
    return e.what();
  }
  return "accepted";
}

// The pole's mass centre in ground by Simbody's kinematics of the flatsos model at q.
Eigen::Vector3d flatsos_pole_mass_center(const fp::MusculoskeletalModel& model, const Eigen::Vector2d& q) {
  SimTK::State s = model.defaultState();
  model.setJointAngles(s, q);
  model.system().realize(s, SimTK::Stage::Position);
  const SimTK::Vec3 c = model.joint(1).getBodyTransform(s) * SimTK::Vec3(model.description().bodies[1].mass_center_m[0],
                                                                        model.description().bodies[1].mass_center_m[1],
                                                                        model.description().bodies[1].mass_center_m[2]);
  return {c[0], c[1], c[2]};
}

}  // namespace

TEST(SliderImport, ASliderJointBecomesAnExactSliderPlacedAsComputedByHand) {
  const fp::OpenSimModel osim = fp::parse_opensim_model(cart_osim(), "cart.osim");
  EXPECT_FALSE(osim.coordinate("rail_x")->rotational);
  const fp::OpenSimImport imported = fp::import_opensim_model(osim, cart_paths(), keep_rail_and_pole());
  const fp::ModelDescription& d = imported.model;
  ASSERT_EQ(d.numJoints(), 2);
  const fp::JointDescription& rail = d.joints[0];
  ASSERT_TRUE(rail.isSlider());
  EXPECT_EQ(rail.coordinate, "rail_x");
  EXPECT_EQ(rail.parent, "ground");
  EXPECT_LT((rail.axis - Eigen::Vector3d(std::cos(kTurn), std::sin(kTurn), 0.0)).norm(), 1e-15);
  EXPECT_LT((rail.location_in_parent_m - Eigen::Vector3d(0.1, 0.9, 0.0)).norm(), 1e-15);  // the joint frame's origin
  EXPECT_EQ(rail.range_rad[0], -0.2);
  EXPECT_EQ(rail.range_rad[1], 0.2);
  // The cart (origin at the rail's frame): its OpenSim origin 5 cm above that frame, turned.
  const fp::BodyDescription& cart = d.bodies[0];
  EXPECT_EQ(cart.name, "cart");
  EXPECT_LT((cart.mass_center_m - turned() * Eigen::Vector3d(0.02, 0.05, 0.01)).norm(), 1e-15);
  Eigen::Matrix3d I;
  I << 0.02, 0.001, 0.0, 0.001, 0.03, 0.0, 0.0, 0.0, 0.04;
  const Eigen::Matrix3d I_ground = turned() * I * turned().transpose();
  EXPECT_LT((cart.principal_inertia_kg_m2 - I_ground.diagonal()).norm(), 1e-15);
  EXPECT_NEAR(cart.product_inertia_kg_m2[0], I_ground(0, 1), 1e-15);
  // The hinge 10 cm along the cart's x from its origin.
  const fp::JointDescription& hinge = d.joints[1];
  EXPECT_FALSE(hinge.isSlider());
  EXPECT_EQ(hinge.parent, "cart");
  EXPECT_LT((hinge.location_in_parent_m - turned() * Eigen::Vector3d(0.1, 0.05, 0.0)).norm(), 1e-12);
  EXPECT_LT((hinge.axis - Eigen::Vector3d::UnitZ()).norm(), 1e-15);

  // Provenance: exact, with the error measured over the range.
  const json provenance = json::parse(d.provenance_json);
  const json& slider = provenance.at("sliders").at("rail");
  EXPECT_EQ(slider.at("exact"), true);
  EXPECT_EQ(slider.at("opensim_joint_type"), "SliderJoint");
  EXPECT_LT(slider.at("joint_point_error_m").get<double>(), 1e-12);
  EXPECT_LT(slider.at("mass_center_error_m").get<double>(), 1e-12);
  EXPECT_TRUE(slider.contains("mass_center_error_at_m"));
  EXPECT_EQ(slider.at("range_m"), json::array({-0.2, 0.2}));
  EXPECT_EQ(provenance.at("pins").at("hinge").at("exact"), true);
  EXPECT_FALSE(provenance.at("pins").contains("rail"));
  for (const auto& note : imported.notes) EXPECT_EQ(note.find("mass centre is up to"), std::string::npos) << note;

  // Muscles: pull shortens 1 m per m of rail (a "moment arm" of 1), push lengthens.
  ASSERT_EQ(d.numMuscles(), 3);
  const double q[2] = {0.1, 0.2};
  double arms[2];
  d.musclePath(0).momentArms(q, arms);
  EXPECT_DOUBLE_EQ(arms[0], 1.0);
  d.musclePath(1).momentArms(q, arms);
  EXPECT_DOUBLE_EQ(arms[0], -1.0);

  // Kinematics: the pole's mass centre where OpenSim's joints put it, over both coordinates.
  const fp::MusculoskeletalModel model(d);
  for (const auto& [x, angle] : {std::pair{-0.2, -1.0}, std::pair{0.0, 0.0}, std::pair{0.13, 0.4}, std::pair{0.2, 1.0}}) {
    const Eigen::Vector3d truth = fp::opensim_body_in_ground(osim, "pole", {{"rail_x", x}, {"pole_angle", angle}}) *
                                  osim.body("pole")->mass_center_m;
    EXPECT_LT((flatsos_pole_mass_center(model, Eigen::Vector2d(x, angle)) - truth).norm(), 1e-12) << x << ", " << angle;
  }
  // Dynamics: the rail carries both bodies up its 0.3 rad slope, F = 5 kg (qdd + g sin 0.3).
  const double qdd = -0.8;
  EXPECT_NEAR(model.inverseDynamics(Eigen::Vector2d(0.1, 0.0), Eigen::Vector2d::Zero(), Eigen::Vector2d(qdd, 0.0))[0],
              5.0 * (qdd + 9.80665 * std::sin(kTurn)), 1e-12);

  // The model file round trip keeps the slider.
  const std::string text = fp::model_json_text(d);
  const fp::ModelDescription back = fp::parse_model_json(text, "cart_rail.json");
  EXPECT_EQ(fp::model_json_text(back), text);
  EXPECT_TRUE(back.joints[0].isSlider());
}

TEST(SliderImport, ACustomJointTranslationOfSlopeMinusOneIsAnExactSlider) {
  // translation2 = 0.02 - rail_x along F's y: the cart slides along -y of the turned frame.
  const std::string rail = custom_rail("<LinearFunction name=\"function\"><coefficients>-1 0.02</coefficients></LinearFunction>");
  const fp::OpenSimModel osim = fp::parse_opensim_model(cart_osim(rail), "cart.osim");
  const fp::ModelDescription d = fp::import_opensim_model(osim, cart_paths(), keep_rail_and_pole()).model;
  ASSERT_TRUE(d.joints[0].isSlider());
  EXPECT_LT((d.joints[0].axis - turned() * Eigen::Vector3d(0.0, -1.0, 0.0)).norm(), 1e-15);
  EXPECT_LT((d.joints[0].location_in_parent_m - (Eigen::Vector3d(0.1, 0.9, 0.0) + turned() * Eigen::Vector3d(0.0, 0.02, 0.0))).norm(),
            1e-15);
  const json slider = json::parse(d.provenance_json).at("sliders").at("rail");
  EXPECT_EQ(slider.at("exact"), true);
  EXPECT_EQ(slider.at("opensim_joint_type"), "CustomJoint");
  const fp::MusculoskeletalModel model(d);
  for (const auto& [x, angle] : {std::pair{-0.15, 0.3}, std::pair{0.2, -0.7}}) {
    const Eigen::Vector3d truth = fp::opensim_body_in_ground(osim, "pole", {{"rail_x", x}, {"pole_angle", angle}}) *
                                  osim.body("pole")->mass_center_m;
    EXPECT_LT((flatsos_pole_mass_center(model, Eigen::Vector2d(x, angle)) - truth).norm(), 1e-12);
  }
}

TEST(SliderImport, ATranslationNoSliderCanFollowIsRefusedSayingWhy) {
  // Twice as fast as its coordinate.
  std::string e = cart_import_error(cart_osim(custom_rail("<LinearFunction name=\"function\"><coefficients>2 0</coefficients></LinearFunction>")));
  EXPECT_NE(e.find("kept coordinate 'rail_x': CustomJoint 'rail' moves its child 2.000000 m per m"), std::string::npos) << e;
  // Slope 1 at the reference but curved: x + x^2 is 40 mm off a straight slide at the range's ends.
  e = cart_import_error(cart_osim(custom_rail("<PolynomialFunction name=\"function\"><coefficients>1 1 0</coefficients></PolynomialFunction>")));
  EXPECT_NE(e.find("does not move its child along one direction at 1 m per m over the range: 40.000 mm off"), std::string::npos) << e;
  // A range outside the coordinate's, in metres.
  fp::OpenSimImportOptions o = keep_rail_and_pole();
  o.ranges["rail_x"] = {-0.1, 0.5};
  e = cart_import_error(cart_osim(), o);
  EXPECT_NE(e.find("range of 'rail_x': [-0.1000 m, 0.5000 m]"), std::string::npos) << e;
  // A muscle across the rail without a fitted path.
  e = cart_import_error(cart_osim().insert(cart_osim().find("</objects></ForceSet>"), osim_muscle("unfitted", "/ground", "/bodyset/cart")));
  EXPECT_NE(e.find("muscle 'unfitted': its path runs across a kept joint"), std::string::npos) << e;
}

// ---- OpenSim's Tug_of_War_Millard -------------------------------------------------------------
// A 20 kg block on a SliderJoint whose frames are turned -1.5708 rad about y (block_tz slides
// along ground z), between two Millard muscles whose GeometryPaths have no fitted
// FunctionBasedPath: the importer refuses them by name. With the two straight paths fitted here
// from the file's path points (ground (0, 0.05, -+0.35), block (0, 0, -+0.05)), the whole import
// works.

namespace {

std::string tug_of_war_path() { return std::string(FLATSOS_SOURCE_DIR) + "/models/opensim/Tug_of_War_Millard.osim"; }

// The muscle's length from its two path points at block_tz = q, by OpenSim's kinematics.
double tug_length(const fp::OpenSimModel& osim, double side, double q) {
  const Eigen::Vector3d on_ground(0.0, 0.05, side * 0.35), on_block(0.0, 0.0, side * 0.05);
  return (on_ground - fp::opensim_body_in_ground(osim, "block", {{"block_tz", q}}) * on_block).norm();
}

}  // namespace

TEST(SliderImport, TugOfWarsSliderIsReadAndItsUnfittedMusclesAreRefusedByName) {
  const fp::OpenSimModel osim = fp::read_opensim_model(tug_of_war_path());
  ASSERT_EQ(osim.joints.size(), 1u);
  EXPECT_EQ(osim.joints[0].type, "SliderJoint");
  const fp::OpenSimCoordinate& tz = *osim.coordinate("block_tz");
  EXPECT_FALSE(tz.rotational);
  EXPECT_DOUBLE_EQ(tz.range[0], -0.3);
  EXPECT_EQ(osim.muscles.size(), 2u);
  // The slide: along ground z (the frames' -1.5708 rad about y, not quite -pi/2).
  const Eigen::Vector3d at_0 = fp::opensim_body_in_ground(osim, "block", {{"block_tz", 0.0}}).translation();
  const Eigen::Vector3d at_1 = fp::opensim_body_in_ground(osim, "block", {{"block_tz", 0.1}}).translation();
  EXPECT_LT(((at_1 - at_0) / 0.1 - Eigen::Vector3d(std::cos(1.5708), 0.0, std::sin(1.5708))).norm(), 1e-12);
  EXPECT_LT((at_0 - Eigen::Vector3d(0.0, 0.05, 0.0)).norm(), 1e-12);  // the block 5 cm above its joint frame

  fp::OpenSimImportOptions o;
  o.keep = {"block_tz"};
  try {
    fp::import_opensim_model(osim, std::vector<fp::OpenSimPolynomialPath>{}, o);
    ADD_FAILURE() << "muscles without fitted paths were accepted";
  } catch (const fp::OpenSimModelError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("muscle 'RightMuscle': its path runs across a kept joint"), std::string::npos) << what;
    EXPECT_NE(what.find("no fitted path"), std::string::npos) << what;
  }
}

TEST(SliderImport, TugOfWarWithFittedStraightPathsIsAnExactSliderUnderTwoMuscles) {
  const fp::OpenSimModel osim = fp::read_opensim_model(tug_of_war_path());
  // Each path is a straight line nearly along the slide: L = 0.3 -+ q to within 1e-11 m. Fitted
  // through the range's ends, checked in between.
  const double lo = -0.08, hi = 0.08;
  std::string paths = "<OpenSimDocument><Set_FunctionBasedPath_><objects>";
  for (const auto& [name, side] : {std::pair{"RightMuscle", -1.0}, std::pair{"LeftMuscle", 1.0}}) {
    const double slope = (tug_length(osim, side, hi) - tug_length(osim, side, lo)) / (hi - lo);
    const double at_0 = tug_length(osim, side, lo) - slope * lo;
    EXPECT_NEAR(at_0, 0.3, 1e-9);
    EXPECT_NEAR(slope, -side, 1e-9);
    EXPECT_NEAR(tug_length(osim, side, 0.03), at_0 + slope * 0.03, 1e-10);
    std::ostringstream c;
    c.precision(17);
    c << at_0 << " " << slope;
    paths += std::string("<FunctionBasedPath name=\"/forceset/") + name +
             "\"><coordinate_paths>/jointset/ground_block/block_tz</coordinate_paths><length_function>"
             "<MultivariatePolynomialFunction><coefficients>" + c.str() +
             "</coefficients><dimension>1</dimension><order>1</order></MultivariatePolynomialFunction></length_function>"
             "</FunctionBasedPath>";
  }
  paths += "</objects></Set_FunctionBasedPath_></OpenSimDocument>";
  fp::OpenSimImportOptions o;
  o.keep = {"block_tz"};
  o.ranges["block_tz"] = {lo, hi};  // the tendons (0.2 m slack) stay taut: L = 0.3 -+ q > 0.2
  const fp::OpenSimImport imported =
      fp::import_opensim_model(osim, fp::parse_opensim_function_based_paths(paths, "tug_paths.xml"), o);
  const fp::ModelDescription& d = imported.model;
  ASSERT_EQ(d.numJoints(), 1);
  ASSERT_TRUE(d.joints[0].isSlider());
  EXPECT_LT((d.joints[0].axis - Eigen::Vector3d(std::cos(1.5708), 0.0, std::sin(1.5708))).norm(), 1e-15);
  EXPECT_LT(d.joints[0].location_in_parent_m.norm(), 1e-15);
  EXPECT_NEAR(d.bodies[0].mass_kg, 20.0, 1e-15);
  EXPECT_LT((d.bodies[0].mass_center_m - Eigen::Vector3d(0.0, 0.05, 0.0)).norm(), 1e-12);
  EXPECT_EQ(json::parse(d.provenance_json).at("sliders").at("ground_block").at("exact"), true);
  ASSERT_EQ(d.numMuscles(), 2);
  EXPECT_EQ(d.muscles[0].parameters.name, "RightMuscle");
  EXPECT_DOUBLE_EQ(d.muscles[0].parameters.max_isometric_force_N, 1000.0);
  EXPECT_DOUBLE_EQ(d.muscles[0].parameters.tendon_slack_length_m, 0.2);
  EXPECT_TRUE(imported.notes.empty()) << imported.notes.front();
  // Gravity is across the slide (its axis has no y): F = 20 kg qdd.
  const fp::MusculoskeletalModel model(d);
  EXPECT_NEAR(model.inverseDynamics(Eigen::VectorXd::Constant(1, 0.05), Eigen::VectorXd::Constant(1, 0.4),
                                    Eigen::VectorXd::Constant(1, 1.5))[0],
              20.0 * 1.5, 1e-12);
  // The right muscle pulls towards -z (it shortens as the block moves that way): moment arm -1.
  double arm = 0.0;
  const double q = 0.0;
  d.musclePath(0).momentArms(&q, &arm);
  EXPECT_NEAR(arm, -1.0, 1e-9);
}
