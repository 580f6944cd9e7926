// OpenSim models made into flatsos models: OpenSim's functions (SimmSpline against its defining
// properties), the importer on a small OpenSim model written here whose lumped masses, inertias
// and joint positions are computed by hand, every refused input named, the model file's round
// trip, and, where OpenSim's example files are present beside the repository (../shared, not
// part of a clone), the seated knee and the sagittal leg: muscle counts, anatomy's signs, and
// lengths and moment arms equal to the fitted polynomials evaluated independently.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <functional>
#include <sstream>
#include <random>
#include <string>

#include "flatsos/muscles/muscle_model.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/io/opensim_function.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"
#include "flatsos/plugin/io/opensim_kinematics.hpp"
#include "flatsos/plugin/io/opensim_model.hpp"
#include "flatsos/plugin/io/opensim_paths.hpp"

namespace fm = flatsos::muscles;
namespace fp = flatsos::plugin;

namespace {

constexpr double kPi = 3.14159265358979323846;

// ---- OpenSim's functions -------------------------------------------------------------------

TEST(OpenSimFunction, SimmSplineInterpolatesReproducesCubicsAndExtrapolatesLinearly) {
  auto cubic = [](double x) { return 0.3 - 0.5 * x + 0.25 * x * x - 0.125 * x * x * x; };
  std::vector<double> x{-1.0, -0.2, 0.5, 1.1, 2.0, 2.4}, y;
  for (double xi : x) y.push_back(cubic(xi));
  const auto f = fp::OpenSimFunction::simmSpline(x, y);
  // Forsythe-Malcolm-Moler end conditions take the end third derivatives from cubics through
  // the end knots: a cubic is reproduced exactly, everywhere inside.
  for (double t = -0.99; t <= 2.39; t += 0.0137) {
    EXPECT_NEAR(f.value(t), cubic(t), 1e-12) << t;
    const double h = 1e-6;
    EXPECT_NEAR(f.derivative(t), (f.value(t + h) - f.value(t - h)) / (2 * h), 1e-8) << t;
  }
  // Beyond the ends: the tangent line at the end knot.
  EXPECT_NEAR(f.value(3.0), cubic(2.4) + 0.6 * f.derivative(2.4), 1e-12);
  EXPECT_NEAR(f.value(-2.0), cubic(-1.0) - 1.0 * f.derivative(-1.0), 1e-12);
  // Through its knots whatever the data, with a continuous second derivative.
  const auto g = fp::OpenSimFunction::simmSpline({0.0, 0.3, 0.4, 1.0, 1.7}, {1.0, -2.0, 0.5, 0.7, 3.0});
  EXPECT_NEAR(g.value(0.3), -2.0, 1e-14);
  EXPECT_NEAR(g.value(1.0), 0.7, 1e-14);
  const double h = 1e-7, side = 1e-6;  // the third derivative jumps at a knot, the second does not
  auto second = [&](double t) { return (g.derivative(t + h) - g.derivative(t - h)) / (2 * h); };
  EXPECT_NEAR(second(0.4 - side), second(0.4 + side), 1e-2);
  EXPECT_GT(std::abs(second(0.4)), 1.0);  // a curve, not a line
  // Two knots: a line; a MultiplierFunction scales.
  const auto line = fp::OpenSimFunction::simmSpline({0.0, 2.0}, {1.0, 2.0}).scaled(3.0);
  EXPECT_DOUBLE_EQ(line.value(1.0), 4.5);
  EXPECT_DOUBLE_EQ(line.derivative(7.0), 1.5);
  EXPECT_THROW(fp::OpenSimFunction::simmSpline({0.0, 0.0, 1.0}, {1.0, 2.0, 3.0}), std::invalid_argument);
}

TEST(OpenSimFunction, PolynomialsAreHighestPowerFirst) {
  const auto p = fp::OpenSimFunction::polynomial({2.0, -1.0, 0.5});  // 2 x^2 - x + 0.5
  EXPECT_DOUBLE_EQ(p.value(3.0), 15.5);
  EXPECT_DOUBLE_EQ(p.derivative(3.0), 11.0);
  EXPECT_THROW(fp::OpenSimFunction::unsupported("GCVSpline").value(0.0), std::runtime_error);
}

// ---- A small OpenSim model written here ----------------------------------------------------
// pelvis (welded: its coordinates held at 0) -> hip (CustomJoint: flexion about z, adduction
// about x) -> thigh -> knee (PinJoint whose frames are turned half a turn about y, so the
// coordinate turns about -z) -> shank -> foot (WeldJoint); patella on the thigh, its coordinate
// coupled to the knee's.

std::string offset(const std::string& name, const std::string& body, const std::string& translation,
                   const std::string& orientation = "0 0 0") {
  return "<PhysicalOffsetFrame name=\"" + name + "\"><socket_parent>/bodyset/" + body + "</socket_parent><translation>" +
         translation + "</translation><orientation>" + orientation + "</orientation></PhysicalOffsetFrame>";
}
std::string coordinate(const std::string& name, const std::string& range) {
  return "<Coordinate name=\"" + name + "\"><default_value>0</default_value><range>" + range + "</range></Coordinate>";
}
std::string axis(const std::string& name, const std::string& coordinates, const std::string& direction,
                 const std::string& function = "") {
  return "<TransformAxis name=\"" + name + "\"><coordinates>" + coordinates + "</coordinates><axis>" + direction + "</axis>" +
         (function.empty() ? std::string() : function) + "</TransformAxis>";
}
const std::string kZero = "<Constant name=\"function\"><value>0</value></Constant>";
const std::string kIdentity = "<LinearFunction name=\"function\"><coefficients>1 0</coefficients></LinearFunction>";
std::string body(const std::string& name, double mass, const std::string& com, const std::string& inertia) {
  return "<Body name=\"" + name + "\"><mass>" + std::to_string(mass) + "</mass><mass_center>" + com + "</mass_center><inertia>" +
         inertia + "</inertia></Body>";
}
std::string muscle(const std::string& name, double fmax, double lopt, double lslack, const std::string& bodies) {
  std::string points;
  int k = 0;
  std::istringstream in(bodies);
  for (std::string b; in >> b;)
    points += "<PathPoint name=\"" + name + "-P" + std::to_string(++k) + "\"><socket_parent_frame>/bodyset/" + b +
              "</socket_parent_frame><location>0 0 0</location></PathPoint>";
  return "<Millard2012EquilibriumMuscle name=\"" + name + "\"><GeometryPath name=\"path\"><PathPointSet><objects>" + points +
         "</objects></PathPointSet></GeometryPath><max_isometric_force>" + std::to_string(fmax) +
         "</max_isometric_force><optimal_fiber_length>" + std::to_string(lopt) + "</optimal_fiber_length><tendon_slack_length>" +
         std::to_string(lslack) + "</tendon_slack_length><pennation_angle_at_optimal>0.05</pennation_angle_at_optimal>" +
         (name == "vas" ? "<minimum_activation>0.02</minimum_activation>" : "") +
         "<FiberForceLengthCurve name=\"f\"><strain_at_one_norm_force>0.6</strain_at_one_norm_force></FiberForceLengthCurve>"
         "</Millard2012EquilibriumMuscle>";
}

std::string small_osim(const std::string& extra_muscles = "") {
  const std::string half_turn_y = "0 3.141592653589793 0";
  return "<?xml version=\"1.0\" encoding=\"UTF-8\" ?><OpenSimDocument Version=\"40500\"><Model name=\"small_leg\">"
         "<gravity>0 -9.80665 0</gravity><credits>written for flatsos' tests</credits><BodySet><objects>" +
         body("pelvis", 10.0, "0 0 0", "0.1 0.1 0.1 0 0 0") + body("thigh", 8.0, "0 -0.2 0", "0.1 0.02 0.1 0 0 0") +
         body("shank", 3.0, "0 -0.18 0", "0.04 0.005 0.04 0 0 0") + body("foot", 1.0, "0.05 -0.02 0", "0.001 0.004 0.004 0 0 0") +
         body("patella", 0.1, "0 0 0", "0.00001 0.00001 0.00001 0 0 0") +
         "</objects></BodySet><JointSet><objects>"
         "<CustomJoint name=\"ground_pelvis\"><socket_parent_frame>/ground</socket_parent_frame><socket_child_frame>pelvis_offset"
         "</socket_child_frame><coordinates>" +
         coordinate("pelvis_tilt", "-1.57 1.57") + coordinate("pelvis_ty", "-1 2") + "</coordinates><frames>" +
         offset("pelvis_offset", "pelvis", "0 0 0") + "</frames><SpatialTransform>" + axis("rotation1", "pelvis_tilt", "0 0 1", kIdentity) +
         axis("rotation2", "", "1 0 0", kZero) + axis("rotation3", "", "0 1 0", kZero) + axis("translation1", "", "1 0 0", kZero) +
         axis("translation2", "pelvis_ty", "0 1 0", kIdentity) + axis("translation3", "", "0 0 1", kZero) +
         "</SpatialTransform></CustomJoint>"
         "<CustomJoint name=\"hip\"><socket_parent_frame>pelvis_offset</socket_parent_frame><socket_child_frame>thigh_offset"
         "</socket_child_frame><coordinates>" +
         coordinate("hip_flexion", "-0.5 2.0") + coordinate("hip_adduction", "-0.8 0.5") + "</coordinates><frames>" +
         offset("pelvis_offset", "pelvis", "0 -0.1 0.08") + offset("thigh_offset", "thigh", "0 0 0") + "</frames><SpatialTransform>" +
         axis("rotation1", "hip_flexion", "0 0 1", kIdentity) + axis("rotation2", "hip_adduction", "1 0 0") +
         axis("rotation3", "", "0 1 0", kZero) + axis("translation1", "", "1 0 0", kZero) + axis("translation2", "", "0 1 0", kZero) +
         axis("translation3", "", "0 0 1", kZero) + "</SpatialTransform></CustomJoint>"
         "<PinJoint name=\"knee\"><socket_parent_frame>thigh_offset</socket_parent_frame><socket_child_frame>shank_offset"
         "</socket_child_frame><coordinates>" +
         coordinate("knee_angle", "0 2.0") + "</coordinates><frames>" + offset("thigh_offset", "thigh", "0 -0.4 0", half_turn_y) +
         offset("shank_offset", "shank", "0 0 0", half_turn_y) + "</frames></PinJoint>"
         "<WeldJoint name=\"ankle_weld\"><socket_parent_frame>shank_offset</socket_parent_frame><socket_child_frame>/bodyset/foot"
         "</socket_child_frame><frames>" +
         offset("shank_offset", "shank", "0 -0.4 0") + "</frames></WeldJoint>"
         "<CustomJoint name=\"patellofemoral\"><socket_parent_frame>thigh_offset</socket_parent_frame><socket_child_frame>"
         "/bodyset/patella</socket_child_frame><coordinates>" +
         coordinate("knee_beta", "-10 10") + "</coordinates><frames>" + offset("thigh_offset", "thigh", "0.05 -0.4 0") +
         "</frames><SpatialTransform>" + axis("rotation1", "knee_beta", "0 0 1", kIdentity) + axis("rotation2", "", "0 1 0", kZero) +
         axis("rotation3", "", "1 0 0", kZero) + axis("translation1", "", "1 0 0", kZero) + axis("translation2", "", "0 1 0", kZero) +
         axis("translation3", "", "0 0 1", kZero) + "</SpatialTransform></CustomJoint>"
         "</objects></JointSet><ConstraintSet><objects><CoordinateCouplerConstraint name=\"patella_con\"><isEnforced>true</isEnforced>"
         "<coupled_coordinates_function><LinearFunction><coefficients>1 0</coefficients></LinearFunction>"
         "</coupled_coordinates_function><independent_coordinate_names>knee_angle</independent_coordinate_names>"
         "<dependent_coordinate_name>knee_beta</dependent_coordinate_name><scale_factor>1</scale_factor>"
         "</CoordinateCouplerConstraint></objects></ConstraintSet><ForceSet><objects>" +
         muscle("vas", 1000.0, 0.1, 0.15, "thigh shank") + muscle("ham", 800.0, 0.1, 0.3, "pelvis shank") +
         muscle("hipflex", 600.0, 0.1, 0.1, "pelvis thigh") + muscle("slacky", 300.0, 0.05, 0.15, "thigh shank") + extra_muscles +
         "<CoordinateActuator name=\"reserve\"><coordinate>knee_angle</coordinate></CoordinateActuator>"
         "</objects></ForceSet></Model></OpenSimDocument>";
}

std::string fitted(const std::string& name, const std::string& coordinates, int dimension, int order, const std::string& c) {
  return "<FunctionBasedPath name=\"/forceset/" + name + "\"><coordinate_paths>" + coordinates +
         "</coordinate_paths><length_function><MultivariatePolynomialFunction><coefficients>" + c + "</coefficients><dimension>" +
         std::to_string(dimension) + "</dimension><order>" + std::to_string(order) +
         "</order></MultivariatePolynomialFunction></length_function></FunctionBasedPath>";
}

std::vector<fp::OpenSimPolynomialPath> small_paths() {
  // OpenSim's order: (knee) 1, q, q^2; (hip, knee) order 1: 1, knee, hip.
  return fp::parse_opensim_function_based_paths(
      "<OpenSimDocument><Set_FunctionBasedPath_><objects>" + fitted("vas", "/jointset/knee/knee_angle", 1, 2, "0.30 0.04 0.001") +
          fitted("ham", "/jointset/hip/hip_flexion /jointset/knee/knee_angle", 2, 1, "0.40 -0.03 0.05") +
          fitted("hipflex", "/jointset/hip/hip_flexion", 1, 1, "0.25 -0.04") +
          fitted("slacky", "/jointset/knee/knee_angle", 1, 1, "0.20 -0.05") +
          fitted("other_leg_muscle", "/jointset/hip/hip_adduction", 1, 1, "0.3 0.01") +
          "</objects></Set_FunctionBasedPath_></OpenSimDocument>",
      "paths.xml");
}

fp::OpenSimImportOptions seated(double hip_deg = 90.0) {
  fp::OpenSimImportOptions o;
  o.keep = {"knee_angle"};
  o.hold = {{"hip_flexion", hip_deg * kPi / 180.0}};
  return o;
}

std::string import_error(const std::string& osim, const fp::OpenSimImportOptions& options) {
  try {
    fp::import_opensim_model(fp::parse_opensim_model(osim, "small.osim"), small_paths(), options);
  } catch (const fp::OpenSimModelError& e) {
    return e.what();
  }
  return "accepted";
}

}  // namespace

TEST(OpenSimModelFile, ReadsBodiesJointsCouplersAndMuscles) {
  const fp::OpenSimModel m = fp::parse_opensim_model(small_osim(), "small.osim");
  EXPECT_EQ(m.name, "small_leg");
  ASSERT_EQ(m.bodies.size(), 5u);
  EXPECT_DOUBLE_EQ(m.body("thigh")->inertia_kg_m2(1, 1), 0.02);
  EXPECT_EQ(m.joint("knee")->type, "PinJoint");
  EXPECT_EQ(m.joint("knee")->parent_body, "thigh");
  EXPECT_EQ(m.jointOfChild("foot")->name, "ankle_weld");
  EXPECT_FALSE(m.coordinate("pelvis_ty")->rotational);
  EXPECT_TRUE(m.coordinate("hip_adduction")->rotational);
  EXPECT_EQ(m.couplerOf("knee_beta")->independent, "knee_angle");
  ASSERT_EQ(m.muscles.size(), 4u);  // the CoordinateActuator is not a muscle
  EXPECT_DOUBLE_EQ(m.muscle("vas")->passive_fiber_strain_at_one_norm_force, 0.6);
  EXPECT_DOUBLE_EQ(m.muscle("vas")->tendon_strain_at_one_norm_force, 0.049);  // Millard's default
  EXPECT_DOUBLE_EQ(m.muscle("vas")->minimum_activation, 0.02);
  EXPECT_DOUBLE_EQ(m.muscle("ham")->minimum_activation, 0.01);  // Millard's default
  EXPECT_EQ(m.muscle("ham")->path_bodies, (std::vector<std::string>{"pelvis", "shank"}));
  // The hip flexed 90 deg puts the thigh horizontal, forward (+x).
  const Eigen::Isometry3d shank = fp::opensim_body_in_ground(m, "shank", {{"hip_flexion", kPi / 2}});
  EXPECT_LT((shank.translation() - Eigen::Vector3d(0.4, -0.1, 0.08)).norm(), 1e-12);
  // The knee's frames are turned half a turn about y: its coordinate turns about -z.
  const auto rate = fp::opensim_joint_rate(*m.joint("knee"), {}, "knee_angle");
  EXPECT_LT((rate.dominant_axis - Eigen::Vector3d::UnitZ()).norm(), 1e-12);  // in F
  const Eigen::Matrix3d R_thigh_F = m.joint("knee")->parent_offset.linear();
  EXPECT_LT((R_thigh_F * rate.dominant_axis + Eigen::Vector3d::UnitZ()).norm(), 1e-12);
}

TEST(OpenSimModelFile, BadDocumentsAreNamed) {
  auto error = [](const std::string& xml) {
    try {
      fp::parse_opensim_model(xml, "bad.osim");
    } catch (const fp::OpenSimFileError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(error("<OpenSimDocument/>").find("no <Model>"), std::string::npos);
  std::string no_mass = small_osim();
  no_mass.replace(no_mass.find("<mass>8"), 6, "<mas>8");
  no_mass.replace(no_mass.find("</mass><mass_center>0 -0.2"), 7, "</mas>");
  EXPECT_NE(error(no_mass).find("Body 'thigh'"), std::string::npos) << error(no_mass);
  std::string bad_frame = small_osim();
  bad_frame.replace(bad_frame.find("<socket_parent_frame>thigh_offset</socket_parent_frame><socket_child_frame>shank_offset"),
                    std::string("<socket_parent_frame>thigh_offset").size(), "<socket_parent_frame>femur_offset");
  EXPECT_NE(error(bad_frame).find("PinJoint 'knee'.socket_parent_frame"), std::string::npos) << error(bad_frame);
  std::string nan = small_osim();
  nan.replace(nan.find("1000.000000"), 11, "many");
  EXPECT_NE(error(nan).find("'vas'.max_isometric_force"), std::string::npos) << error(nan);
  EXPECT_THROW(fp::read_opensim_model("/nonexistent/model.osim"), fp::OpenSimFileError);
}

TEST(OpenSimImport, ASeatedKneeLumpsShankFootAndPatellaAsComputedByHand) {
  const fp::OpenSimImport imported =
      fp::import_opensim_model(fp::parse_opensim_model(small_osim(), "small.osim"), small_paths(), seated());
  const fp::ModelDescription& model = imported.model;
  ASSERT_EQ(model.numJoints(), 1);
  const fp::JointDescription& knee = model.joints[0];
  EXPECT_EQ(knee.name, "knee");
  EXPECT_EQ(knee.coordinate, "knee_angle");
  EXPECT_EQ(knee.parent, "ground");  // pelvis and thigh welded
  EXPECT_LT((knee.axis + Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  EXPECT_EQ(knee.range_rad[0], 0.0);
  EXPECT_EQ(knee.range_rad[1], 2.0);
  // Hip centre (0, -0.1, 0.08), thigh horizontal: the knee 0.4 m forward of it.
  EXPECT_LT((knee.location_in_parent_m - Eigen::Vector3d(0.4, -0.1, 0.08)).norm(), 1e-12);

  // By hand, relative to the knee, ground axes (the shank turned 90 deg about z: body -y is +x):
  // shank 3 kg at (0.18, 0, 0); foot 1 kg at 0.4 m plus its (0.05, -0.02) turned: (0.42, 0.05, 0);
  // patella 0.1 kg on the thigh 0.4 forward and 0.05 up: (0, 0.05, 0).
  ASSERT_EQ(model.bodies.size(), 1u);
  const fp::BodyDescription& b = model.bodies[0];
  EXPECT_EQ(b.name, "shank");
  EXPECT_NEAR(b.mass_kg, 4.1, 1e-12);
  const Eigen::Vector3d com = (3.0 * Eigen::Vector3d(0.18, 0, 0) + 1.0 * Eigen::Vector3d(0.42, 0.05, 0) +
                               0.1 * Eigen::Vector3d(0, 0.05, 0)) / 4.1;
  EXPECT_LT((b.mass_center_m - com).norm(), 1e-12);
  // Inertias turned (x and y swap), then moved to the common mass centre (parallel axes).
  Eigen::Matrix3d I = Eigen::Vector3d(0.005, 0.04, 0.04).asDiagonal();
  I += Eigen::Matrix3d(Eigen::Vector3d(0.004, 0.001, 0.004).asDiagonal());
  I += Eigen::Matrix3d(Eigen::Vector3d(1e-5, 1e-5, 1e-5).asDiagonal());
  for (const auto& [mass, at] : {std::pair<double, Eigen::Vector3d>{3.0, {0.18, 0, 0}}, {1.0, {0.42, 0.05, 0}}, {0.1, {0, 0.05, 0}}}) {
    const Eigen::Vector3d d = at - com;
    I += mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  }
  EXPECT_LT((b.principal_inertia_kg_m2 - I.diagonal()).norm(), 1e-12);
  EXPECT_NEAR(b.product_inertia_kg_m2[0], I(0, 1), 1e-12);
  EXPECT_NEAR(b.product_inertia_kg_m2[1], I(0, 2), 1e-12);
  EXPECT_NEAR(b.product_inertia_kg_m2[2], I(1, 2), 1e-12);

  // Muscles: those whose length depends on the knee; the slack one left out and said why.
  ASSERT_EQ(model.numMuscles(), 2);
  EXPECT_EQ(model.muscles[0].parameters.name, "vas");
  EXPECT_EQ(model.muscles[1].parameters.name, "ham");
  EXPECT_DOUBLE_EQ(model.muscles[0].parameters.pennation_angle_at_optimal_rad, 0.05);
  EXPECT_DOUBLE_EQ(model.muscles[0].parameters.passive_fiber_strain_at_one_norm_force, 0.6);
  EXPECT_DOUBLE_EQ(model.muscles[0].parameters.tendon_strain_at_max_force, 0.049);
  EXPECT_DOUBLE_EQ(model.muscles[0].parameters.activation_floor, 0.02);  // OpenSim's minimum activation
  EXPECT_DOUBLE_EQ(model.muscles[1].parameters.activation_floor, 0.01);
  ASSERT_TRUE(model.muscles[1].polynomial_path);
  EXPECT_DOUBLE_EQ(model.muscles[1].polynomial_path->held_coordinates_rad.at("hip_flexion"), kPi / 2);
  bool said = false;
  for (const auto& note : imported.notes) said = said || note.find("'slacky' left out") != std::string::npos;
  EXPECT_TRUE(said);
  // ham: L = 0.40 - 0.03 knee + 0.05 hip (hip held at 90 deg), moment arm 0.03 m (flexor).
  const auto ham = model.musclePath(1);
  const double q = 1.2;
  double arm = 0.0;
  ham.momentArms(&q, &arm);
  EXPECT_NEAR(ham.length(&q), 0.40 - 0.03 * q + 0.05 * kPi / 2, 1e-15);
  EXPECT_NEAR(arm, 0.03, 1e-15);
  const auto vas = model.musclePath(0);
  vas.momentArms(&q, &arm);
  EXPECT_NEAR(arm, -(0.04 + 0.002 * q), 1e-15);  // an extensor

  // A true pin: the pin's point is the joint's own, and OpenSim's bodies follow it exactly
  // except the patella, which turns about its own joint (lumped where it is at 0).
  EXPECT_NE(model.provenance_json.find("\"lumped_bodies\":[\"foot\",\"patella\"]"), std::string::npos) << model.provenance_json;
}

TEST(OpenSimImport, TheModelFileRoundTripsAndRecordsItsProvenance) {
  fp::OpenSimImportOptions options = seated(60.0);
  options.osim_source = "small.osim";
  const fp::ModelDescription model =
      fp::import_opensim_model(fp::parse_opensim_model(small_osim(), "small.osim"), small_paths(), options).model;
  const std::string text = fp::model_json_text(model);
  const fp::ModelDescription back = fp::parse_model_json(text, "round_trip.json");
  EXPECT_EQ(fp::model_json_text(back), text);
  EXPECT_EQ(back.bodies[0].mass_center_m, model.bodies[0].mass_center_m);
  EXPECT_EQ(back.bodies[0].product_inertia_kg_m2, model.bodies[0].product_inertia_kg_m2);
  EXPECT_EQ(back.joints[0].location_in_parent_m, model.joints[0].location_in_parent_m);
  EXPECT_EQ(back.muscles[1].polynomial_path->coefficients, model.muscles[1].polynomial_path->coefficients);
  EXPECT_EQ(back.muscles[1].polynomial_path->held_coordinates_rad, model.muscles[1].polynomial_path->held_coordinates_rad);
  EXPECT_EQ(back.muscles[0].parameters.pennation_angle_at_optimal_rad, 0.05);
  EXPECT_EQ(back.provenance_json, model.provenance_json);
  EXPECT_TRUE(text.find("\"hip_flexion\": 60.0") != std::string::npos ||
              text.find("\"hip_flexion\": 59.99999999999999") != std::string::npos);  // held values, in degrees
  EXPECT_NE(text.find("small.osim"), std::string::npos);
}

TEST(OpenSimImport, EveryRefusedInputIsNamed) {
  const std::string osim = small_osim();
  auto with = [](std::function<void(fp::OpenSimImportOptions&)> change) {
    fp::OpenSimImportOptions o = seated();
    change(o);
    return o;
  };
  auto expect = [&](const fp::OpenSimImportOptions& o, const std::string& words, const std::string& model = "") {
    const std::string e = import_error(model.empty() ? osim : model, o);
    EXPECT_NE(e.find(words), std::string::npos) << e;
  };
  expect(with([](auto& o) { o.keep = {"knee_flexion"}; }), "kept coordinate 'knee_flexion': the OpenSim model has no such coordinate");
  expect(with([](auto& o) { o.keep = {}; }), "no coordinate to keep");
  expect(with([](auto& o) { o.hold["knee_angle"] = 0.1; }), "'knee_angle': both kept and held");
  expect(with([](auto& o) { o.hold["hip_flexion"] = 3.0; }), "held coordinate 'hip_flexion': 171.887 deg is outside its range");
  expect(with([](auto& o) { o.hold["pelvis_ty"] = 5.0; }), "5.0000 m is outside its range");
  expect(with([](auto& o) { o.hold["hip_rotation"] = 0.0; }), "held coordinate 'hip_rotation': the OpenSim model has no such coordinate");
  expect(with([](auto& o) { o.keep = {"hip_flexion", "hip_adduction"}; o.hold.clear(); }), "one pin per joint");
  expect(with([](auto& o) { o.keep = {"knee_beta"}; }), "it follows 'knee_angle'");
  // A translation becomes a slider (test_slider_joints.cpp); no fitted path here depends on it.
  expect(with([](auto& o) { o.keep = {"pelvis_ty"}; o.hold.clear(); }), "no muscle's fitted length depends on the kept");
  expect(with([](auto& o) { o.ranges["knee_angle"] = {0.0, 2.5}; }), "range of 'knee_angle'");
  expect(with([](auto& o) { o.ranges["hip_flexion"] = {0.0, 1.0}; }), "not a kept coordinate");
  expect(with([](auto& o) { o.refuse_slack_muscles = true; }), "muscle 'slacky': its fitted length");
  expect(with([](auto& o) { o.keep = {"hip_flexion", "hip_adduction"}; o.hold.clear(); }), "hip");
  // A muscle across the knee that the paths file does not fit.
  expect(seated(), "muscle 'unfitted': its path runs across a kept joint", small_osim(muscle("unfitted", 500.0, 0.1, 0.1, "thigh shank")));
}

// Pins keep OpenSim's axes in 3-D: the hip's adduction (rotation2, about x after the flexion's
// rotation1 about z held at 90 deg) turns about F's y, 90 deg from the knee's axis, and both
// joints, being one rotation each, are reproduced exactly (the importer's pins go through the
// joint frames' origins and every body that turns with them follows OpenSim's to rounding).
TEST(OpenSimImport, PinsKeepOpenSimsAxesAndJointsOfOneRotationAreExact) {
  fp::OpenSimImportOptions o;
  o.keep = {"hip_adduction", "knee_angle"};
  o.hold = {{"hip_flexion", kPi / 2}};
  const fp::OpenSimImport imported = fp::import_opensim_model(fp::parse_opensim_model(small_osim(), "small.osim"), small_paths(), o);
  const fp::ModelDescription& model = imported.model;
  ASSERT_EQ(model.numJoints(), 2);
  EXPECT_EQ(model.joints[0].name, "hip");
  EXPECT_LT((model.joints[0].axis - Eigen::Vector3d::UnitY()).norm(), 1e-12);
  // The knee's frames are both turned half a turn about y, so its z axis is -z in ground.
  EXPECT_LT((model.joints[1].axis + Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  const nlohmann::json provenance = nlohmann::json::parse(model.provenance_json);
  for (const char* joint : {"hip", "knee"}) {
    EXPECT_TRUE(provenance["pins"][joint]["exact"].get<bool>()) << joint;
    EXPECT_LT(provenance["pins"][joint]["joint_point_error_m"].get<double>(), 1e-12) << joint;
  }
  // The hip carries the thigh alone (the knee's bodies hang from the knee): its mass centre too.
  EXPECT_LT(provenance["pins"]["hip"]["mass_center_error_m"].get<double>(), 1e-12);
  // The patella follows the knee through a coupler on its own path and is lumped where it is at
  // the reference posture: the shank's lumped mass centre is off elsewhere, and said so.
  EXPECT_GT(provenance["pins"]["knee"]["mass_center_error_m"].get<double>(), 1e-4);
}

// A Thelen2003Muscle keeps OpenSim's model and every property the file states (arm26's values
// here); what it leaves out takes OpenSim's Thelen defaults, not another model's. A Millard muscle
// becomes flatsos' Millard model (its curves: test_millard_import.cpp).
TEST(OpenSimImport, AThelenMuscleKeepsOpenSimsModelAndProperties) {
  std::string vas = muscle("vas", 1000.0, 0.1, 0.15, "thigh shank");
  const std::string from = "<Millard2012EquilibriumMuscle name=\"vas\">", to = "</Millard2012EquilibriumMuscle>";
  vas.replace(0, from.size(), "<Thelen2003Muscle name=\"vas\">");
  vas.replace(vas.size() - to.size(), to.size(),
              "<FmaxTendonStrain>0.033</FmaxTendonStrain><KshapeActive>0.5</KshapeActive><KshapePassive>4</KshapePassive>"
              "<Af>0.3</Af><Flen>1.8</Flen><activation_time_constant>0.01</activation_time_constant></Thelen2003Muscle>");
  std::string osim = small_osim();
  const std::string millard_vas = muscle("vas", 1000.0, 0.1, 0.15, "thigh shank");
  osim.replace(osim.find(millard_vas), millard_vas.size(), vas);
  const fp::ModelDescription model = fp::import_opensim_model(fp::parse_opensim_model(osim, "small.osim"), small_paths(), seated()).model;
  const fm::MuscleParameters& p = model.muscles[static_cast<std::size_t>(model.muscleIndex("vas"))].parameters;
  EXPECT_EQ(p.model->name(), "thelen2003");
  EXPECT_DOUBLE_EQ(p.tendon_strain_at_max_force, 0.033);
  EXPECT_DOUBLE_EQ(p.force_length_width * p.force_length_width, 0.5);
  EXPECT_DOUBLE_EQ(p.passive_force_length_shape, 4.0);
  EXPECT_DOUBLE_EQ(p.hill_constant, 0.3);
  EXPECT_DOUBLE_EQ(p.max_eccentric_force_ratio, 1.8);
  EXPECT_DOUBLE_EQ(p.activation_time_constant_s, 0.01);
  EXPECT_DOUBLE_EQ(p.deactivation_time_constant_s, 0.05);  // Thelen's default: the file leaves it out
  EXPECT_DOUBLE_EQ(p.passive_fiber_strain_at_one_norm_force, 0.6);
  EXPECT_DOUBLE_EQ(p.pennation_angle_at_optimal_rad, 0.05);
  const fm::MuscleParameters& ham = model.muscles[static_cast<std::size_t>(model.muscleIndex("ham"))].parameters;
  EXPECT_EQ(ham.model->name(), "millard2012");
  // A property the model refuses is named with the muscle.
  std::string bad = osim;
  bad.replace(bad.find("<Flen>1.8</Flen>"), 16, "<Flen>0.9</Flen>");
  EXPECT_NE(import_error(bad, seated()).find("muscle 'vas': max_eccentric_force_ratio"), std::string::npos)
      << import_error(bad, seated());
}

// ---- OpenSim's example model, where it is present ------------------------------------------

namespace {

std::string shared_file(const std::string& name) { return std::string(FLATSOS_SOURCE_DIR) + "/../shared/opensim/" + name; }
bool shared_present() { return std::ifstream(shared_file("subject_walk_scaled.osim")).good(); }

// OpenSim's MultivariatePolynomialFunction written out independently: the exponents in nested
// loops, the first argument outermost, each ascending; value and analytic partials.
void evaluate_independently(const fp::OpenSimPolynomialPath& p, const std::vector<double>& x, double& value,
                            std::vector<double>& partial) {
  const int d = static_cast<int>(x.size());
  value = 0.0;
  partial.assign(x.size(), 0.0);
  std::size_t term = 0;
  std::vector<int> e(x.size(), 0);
  std::function<void(int, int)> loop = [&](int k, int left) {
    if (k == d) {
      const double c = p.coefficients.at(term++);
      double monomial = c;
      for (int i = 0; i < d; ++i) monomial *= std::pow(x[i], e[i]);
      value += monomial;
      for (int i = 0; i < d; ++i) {
        if (e[i] == 0) continue;
        double t = c * e[i] * std::pow(x[i], e[i] - 1);
        for (int j = 0; j < d; ++j)
          if (j != i) t *= std::pow(x[j], e[j]);
        partial[i] += t;
      }
      return;
    }
    for (e[k] = 0; e[k] <= left; ++e[k]) loop(k + 1, left - e[k]);
  };
  loop(0, p.order);
  ASSERT_EQ(term, p.coefficients.size());
}

struct Imported {
  fp::ModelDescription model;
  std::vector<fp::OpenSimPolynomialPath> paths;
  fp::OpenSimModel osim;
};

Imported import_shared(const fp::OpenSimImportOptions& options) {
  Imported out;
  out.osim = fp::read_opensim_model(shared_file("subject_walk_scaled.osim"));
  out.paths = fp::read_opensim_function_based_paths(shared_file("subject_walk_scaled_FunctionBasedPathSet.xml"));
  out.model = fp::import_opensim_model(out.osim, out.paths, options).model;
  return out;
}

// Lengths and moment arms at 20 random postures in range equal the file's polynomials.
void expect_paths_equal_the_file(const Imported& imported) {
  std::mt19937_64 rng(7);
  const fp::ModelDescription& model = imported.model;
  for (int j = 0; j < model.numMuscles(); ++j) {
    const auto& name = model.muscles[j].parameters.name;
    const auto source = std::find_if(imported.paths.begin(), imported.paths.end(), [&](const auto& p) { return p.muscle == name; });
    ASSERT_NE(source, imported.paths.end()) << name;
    const auto path = model.musclePath(j);
    for (int trial = 0; trial < 20; ++trial) {
      Eigen::VectorXd q(model.numJoints());
      for (int i = 0; i < model.numJoints(); ++i)
        q[i] = std::uniform_real_distribution<double>(model.joints[i].range_rad[0], model.joints[i].range_rad[1])(rng);
      std::vector<double> x;
      for (const std::string& c : source->coordinates) {
        const int i = static_cast<int>(std::find_if(model.joints.begin(), model.joints.end(),
                                                    [&](const auto& d) { return d.coordinate == c; }) - model.joints.begin());
        x.push_back(i < model.numJoints() ? q[i] : model.muscles[j].polynomial_path->held_coordinates_rad.at(c));
      }
      double length = 0.0;
      std::vector<double> partial;
      evaluate_independently(*source, x, length, partial);
      Eigen::VectorXd arms(model.numJoints());
      path.momentArms(q.data(), arms.data());
      EXPECT_NEAR(path.length(q.data()), length, 1e-12) << name;
      for (std::size_t a = 0; a < x.size(); ++a) {
        const auto joint = std::find_if(model.joints.begin(), model.joints.end(), [&](const auto& d) { return d.coordinate == source->coordinates[a]; });
        if (joint != model.joints.end()) {
          EXPECT_NEAR(arms[joint - model.joints.begin()], -partial[a], 1e-12) << name;
        }
      }
    }
  }
}

double arm_at(const fp::ModelDescription& model, const std::string& muscle, const std::string& coordinate, const Eigen::VectorXd& q) {
  const int j = model.muscleIndex(muscle);
  EXPECT_GE(j, 0) << muscle;
  Eigen::VectorXd arms(model.numJoints());
  model.musclePath(j).momentArms(q.data(), arms.data());
  for (int i = 0; i < model.numJoints(); ++i)
    if (model.joints[i].coordinate == coordinate) return arms[i];
  ADD_FAILURE() << coordinate;
  return 0.0;
}

fp::OpenSimImportOptions seated_knee_options() {
  fp::OpenSimImportOptions o;
  o.name = "seated_knee_r";
  o.keep = {"knee_angle_r"};
  o.hold = {{"hip_flexion_r", 60.0 * kPi / 180.0}};
  o.ranges = {{"knee_angle_r", {0.0, 115.0 * kPi / 180.0}}};
  return o;
}

fp::OpenSimImportOptions sagittal_leg_options() {
  fp::OpenSimImportOptions o;
  o.name = "sagittal_leg_r";
  o.keep = {"hip_flexion_r", "knee_angle_r", "ankle_angle_r"};
  o.ranges = {{"hip_flexion_r", {-10.0 * kPi / 180.0, 60.0 * kPi / 180.0}},
              {"knee_angle_r", {0.0, 90.0 * kPi / 180.0}},
              {"ankle_angle_r", {-30.0 * kPi / 180.0, 30.0 * kPi / 180.0}}};
  return o;
}

}  // namespace

TEST(OpenSimExampleModel, TheSeatedKneeHasThe13KneeMusclesWithAnatomysSigns) {
  if (!shared_present()) GTEST_SKIP() << "OpenSim's example files are not beside the repository";
  const Imported knee = import_shared(seated_knee_options());
  EXPECT_EQ(knee.model.numMuscles(), 13);
  expect_paths_equal_the_file(knee);
  for (double deg : {10.0, 60.0, 100.0}) {
    const Eigen::VectorXd q = Eigen::VectorXd::Constant(1, deg * kPi / 180.0);
    for (const char* extensor : {"vasint_r", "vaslat_r", "vasmed_r", "recfem_r"}) EXPECT_LT(arm_at(knee.model, extensor, "knee_angle_r", q), 0.0) << extensor;
    for (const char* flexor : {"bfsh_r", "bflh_r", "semiten_r", "gasmed_r"}) EXPECT_GT(arm_at(knee.model, flexor, "knee_angle_r", q), 0.0) << flexor;
  }
  // The lumped shank: tibia, patella, talus, calcaneus and toes, as OpenSim gives their masses.
  double mass = 0.0;
  for (const char* b : {"tibia_r", "patella_r", "talus_r", "calcn_r", "toes_r"}) mass += knee.osim.body(b)->mass_kg;
  EXPECT_NEAR(knee.model.bodies[0].mass_kg, mass, 1e-12);
}

TEST(OpenSimExampleModel, TheSagittalLegHas40MusclesWithAnatomysSigns) {
  if (!shared_present()) GTEST_SKIP() << "OpenSim's example files are not beside the repository";
  const Imported leg = import_shared(sagittal_leg_options());
  EXPECT_EQ(leg.model.numMuscles(), 40);
  expect_paths_equal_the_file(leg);
  const Eigen::VectorXd q = Eigen::Vector3d(20.0, 40.0, 0.0) * kPi / 180.0;
  EXPECT_GT(arm_at(leg.model, "iliacus_r", "hip_flexion_r", q), 0.0);
  EXPECT_LT(arm_at(leg.model, "soleus_r", "ankle_angle_r", q), 0.0);
  EXPECT_GT(arm_at(leg.model, "tibant_r", "ankle_angle_r", q), 0.0);
  EXPECT_LT(arm_at(leg.model, "vaslat_r", "knee_angle_r", q), 0.0);
  double mass = 0.0;
  for (const char* b : {"femur_r", "tibia_r", "patella_r", "talus_r", "calcn_r", "toes_r"}) mass += leg.osim.body(b)->mass_kg;
  double total = 0.0;
  for (const auto& b : leg.model.bodies) total += b.mass_kg;
  EXPECT_NEAR(total, mass, 1e-12);
  EXPECT_NEAR(leg.model.bodies[0].mass_kg, leg.osim.body("femur_r")->mass_kg, 1e-12);
}

TEST(OpenSimExampleModel, TheShippedModelsAreWhatTheImporterMakes) {
  if (!shared_present()) GTEST_SKIP() << "OpenSim's example files are not beside the repository";
  for (const auto& [file, options] : {std::pair<std::string, fp::OpenSimImportOptions>{"seated_knee_r", seated_knee_options()},
                                      {"sagittal_leg_r", sagittal_leg_options()}}) {
    fp::OpenSimImportOptions o = options;
    o.millard_with_flatsos_laws = true;  // as the shipped models were made
    o.osim_source = "subject_walk_scaled.osim";
    o.paths_source = "subject_walk_scaled_FunctionBasedPathSet.xml";
    const fp::ModelDescription made = import_shared(o).model;
    const fp::ModelDescription shipped = fp::load_model_file(std::string(FLATSOS_SOURCE_DIR) + "/models/" + file + ".json");
    fp::ModelDescription without_scenarios = shipped;
    without_scenarios.scenarios.clear();
    EXPECT_EQ(fp::model_json_text(without_scenarios), fp::model_json_text(made)) << file;
  }
}
