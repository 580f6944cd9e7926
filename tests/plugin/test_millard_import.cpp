// OpenSim's Millard2012EquilibriumMuscle imported as OpenSim models it: its curves from the
// .osim's curve properties, compared with curves built here from the numbers read by eye in the
// files (never from the importer); what flatsos cannot represent refused or noted by name; and
// model files that carry a Millard muscle's curves, written and read back to equal curves.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"

#include <cmath>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "flatsos/muscles/millard2012_muscle.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"
#include "flatsos/plugin/io/opensim_model.hpp"

namespace {

namespace fm = flatsos::muscles;
namespace fp = flatsos::plugin;
using nlohmann::json;

const std::string kTug = std::string(FLATSOS_SOURCE_DIR) + "/models/opensim/Tug_of_War_Millard.osim";

std::string file_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Every occurrence of `from` in `text` replaced (both muscles of the Tug of War alike).
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  for (; at != std::string::npos; at = text.find(from, at + to.size())) text.replace(at, from.size(), to);
  return text;
}

// Every `element`'s content replaced.
std::string with_content(std::string text, const std::string& element, const std::string& content) {
  std::size_t at = text.find("<" + element + " ");
  EXPECT_NE(at, std::string::npos) << element;
  for (; at != std::string::npos; at = text.find("<" + element + " ", at + 1)) {
    const std::size_t begin = text.find('>', at) + 1, end = text.find("</" + element + ">", begin);
    text.replace(begin, end - begin, content);
  }
  return text;
}

fp::OpenSimImport import_text(const std::string& osim) {
  const std::string path = ::testing::TempDir() + "millard_import.osim";
  std::ofstream(path) << osim;
  return fp::import_opensim_file(path);
}

std::string import_error(const std::string& osim) {
  try {
    import_text(osim);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "accepted";
}

const fm::Millard2012Muscle& millard(const fm::MuscleParameters& p) {
  const auto* m = dynamic_cast<const fm::Millard2012Muscle*>(p.model.get());
  if (!m) throw std::runtime_error("muscle '" + p.name + "' is not a Millard2012Muscle but " + p.model->name());
  return *m;
}

// The two sets of curves agree at points across each curve's whole range (ends and beyond).
void expect_same_curves(const fm::Millard2012Curves& a, const fm::Millard2012Curves& b, const std::string& what) {
  for (double x : {0.3, 0.45, 0.5, 0.6, 0.7, 0.9, 1.0, 1.3, 1.7, 1.9})
    EXPECT_EQ(a.active_force_length.evaluate(x).value, b.active_force_length.evaluate(x).value) << what << " fL(" << x << ")";
  for (double x : {-1.1, -0.95, -0.5, -0.1, 0.0, 0.1, 0.5, 0.95, 1.1})
    EXPECT_EQ(a.force_velocity.evaluate(x).value, b.force_velocity.evaluate(x).value) << what << " fV(" << x << ")";
  for (double x : {0.9, 1.05, 1.2, 1.4, 1.6, 1.8})
    EXPECT_EQ(a.fiber_force_length.evaluate(x).value, b.fiber_force_length.evaluate(x).value) << what << " fPE(" << x << ")";
  for (double x : {0.99, 1.005, 1.02, 1.04, 1.05, 1.07})
    EXPECT_EQ(a.tendon_force_length.evaluate(x).value, b.tendon_force_length.evaluate(x).value) << what << " fSE(" << x << ")";
}

// The Tug of War's curve properties, as its file states them (both muscles alike); what it
// leaves out is OpenSim's default (force-velocity curviness 0.6 and 0.9, the optional passive
// and tendon properties computed).
fm::Millard2012CurveParameters tug_curves_by_eye() {
  fm::Millard2012CurveParameters c;
  c.active_force_length = {0.4441, 0.6259, 1.8123, 0.8616, 0.0};
  c.force_velocity = {0.0, 0.25, 5.0, 0.0, 0.15, 1.4, 0.6, 0.9};
  c.fiber_force_length.strain_at_zero_force = 0.0;
  c.fiber_force_length.strain_at_one_norm_force = 0.6;
  c.tendon_force_length.strain_at_one_norm_force = 0.049;
  return c;
}

TEST(MillardImport, TheTugOfWarsCurvePropertiesAreRead) {
  const fp::OpenSimModel osim = fp::read_opensim_model(kTug);
  const auto& p = osim.muscle("RightMuscle")->properties;
  EXPECT_EQ(p.at("ActiveForceLengthCurve/transition_norm_fiber_length"), 0.6259);
  EXPECT_EQ(p.at("ForceVelocityCurve/eccentric_slope_near_vmax"), 0.15);
  EXPECT_EQ(p.at("FiberForceLengthCurve/strain_at_one_norm_force"), 0.6);
  EXPECT_EQ(p.at("ignore_tendon_compliance"), 0.0);  // a boolean, false
  EXPECT_EQ(p.count("TendonForceLengthCurve/stiffness_at_one_norm_force"), 0u);  // empty: unset
}

TEST(MillardImport, TheTugOfWarsMusclesHaveTheCurvesItsFileStates) {
  const fp::ModelDescription model = fp::import_opensim_file(kTug).model;
  ASSERT_EQ(model.numMuscles(), 2);
  const fm::Millard2012Curves by_eye = fm::millard2012_curves(tug_curves_by_eye());
  for (const auto& m : model.muscles) {
    const fm::MuscleParameters& p = m.parameters;
    ASSERT_EQ(p.model->name(), "millard2012") << p.name;
    expect_same_curves(millard(p).curves(), by_eye, p.name);
    EXPECT_TRUE(millard(p).damped());
    EXPECT_EQ(p.fiber_damping, 0.1);       // OpenSim's default: the file states none
    EXPECT_EQ(p.activation_floor, 0.01);  // OpenSim's minimum_activation default
    EXPECT_EQ(p.passive_fiber_strain_at_one_norm_force, 0.6);
    EXPECT_EQ(p.tendon_strain_at_max_force, 0.049);
    EXPECT_EQ(millard(p).maximumPennationAngle(), std::acos(0.1));
  }
  // Not OpenSim's default curve: the file's transition (0.6259, default 0.73) shows at 0.6.
  const fm::Millard2012Curves defaults = fm::Millard2012Muscle().curves();
  EXPECT_GT(std::abs(millard(model.muscles[0].parameters).curves().active_force_length.evaluate(0.6).value -
                     defaults.active_force_length.evaluate(0.6).value),
            1e-3);
  const auto provenance = json::parse(model.provenance_json);
  EXPECT_NE(provenance["approximations"].dump().find("Millard2012EquilibriumMuscle (its curves from the file's curve properties"),
            std::string::npos);
}

// Non-default properties in every curve, a damping, a floor and a maximum pennation.
std::string non_default_tug() {
  std::string osim = file_text(kTug);
  osim = replaced(osim, "<min_norm_active_fiber_length>0.44409999999999999</min_norm_active_fiber_length>",
                  "<min_norm_active_fiber_length>0.5</min_norm_active_fiber_length>");
  osim = replaced(osim, "<concentric_slope_near_vmax>0.25</concentric_slope_near_vmax>",
                  "<concentric_slope_near_vmax>0.2</concentric_slope_near_vmax><concentric_curviness>0.7</concentric_curviness>");
  osim = replaced(osim, "<strain_at_one_norm_force>0.59999999999999998</strain_at_one_norm_force>",
                  "<strain_at_one_norm_force>0.5</strain_at_one_norm_force>");
  osim = with_content(osim, "TendonForceLengthCurve",
                      "<strain_at_one_norm_force>0.04</strain_at_one_norm_force><stiffness_at_one_norm_force>40"
                      "</stiffness_at_one_norm_force><norm_force_at_toe_end>0.6</norm_force_at_toe_end><curviness>0.4</curviness>");
  osim = replaced(osim, "<deactivation_time_constant>0.040000000000000001</deactivation_time_constant>",
                  "<deactivation_time_constant>0.05</deactivation_time_constant><fiber_damping>0.05</fiber_damping>"
                  "<minimum_activation>0.02</minimum_activation><maximum_pennation_angle>1.2</maximum_pennation_angle>");
  return osim;
}

fm::Millard2012CurveParameters non_default_curves_by_eye() {
  fm::Millard2012CurveParameters c = tug_curves_by_eye();
  c.active_force_length.min_norm_active_fiber_length = 0.5;
  c.force_velocity.concentric_slope_near_vmax = 0.2;
  c.force_velocity.concentric_curviness = 0.7;
  c.fiber_force_length.strain_at_one_norm_force = 0.5;
  c.tendon_force_length = {0.04, 40.0, 0.6, 0.4};
  return c;
}

TEST(MillardImport, NonDefaultCurvePropertiesGiveThoseCurves) {
  const fp::ModelDescription model = import_text(non_default_tug()).model;
  const fm::Millard2012Curves by_eye = fm::millard2012_curves(non_default_curves_by_eye());
  for (const auto& m : model.muscles) {
    const fm::MuscleParameters& p = m.parameters;
    expect_same_curves(millard(p).curves(), by_eye, p.name);
    EXPECT_EQ(p.fiber_damping, 0.05);
    EXPECT_EQ(p.activation_floor, 0.02);
    EXPECT_EQ(p.deactivation_time_constant_s, 0.05);
    EXPECT_EQ(p.tendon_strain_at_max_force, 0.04);
    EXPECT_EQ(p.passive_fiber_strain_at_one_norm_force, 0.5);
    EXPECT_EQ(millard(p).maximumPennationAngle(), 1.2);
    // Independent landmarks: the steep ascending limb starts where the file says (0 there,
    // damped), the tendon reaches one force at its strain, and its stiffness there is 40.
    EXPECT_EQ(millard(p).curves().active_force_length.evaluate(0.5).value, 0.0);
    EXPECT_GT(millard(p).curves().active_force_length.evaluate(0.52).value, 0.0);
    EXPECT_NEAR(millard(p).curves().tendon_force_length.evaluate(1.04).value, 1.0, 1e-12);
    EXPECT_NEAR(millard(p).curves().tendon_force_length.evaluate(1.04).first, 40.0, 1e-9);
  }
}

TEST(MillardImport, WhatFlatsosCannotRepresentIsRefusedOrNotedByName) {
  const std::string tug = file_text(kTug);
  const std::string rigid = replaced(tug, "<ignore_tendon_compliance>false", "<ignore_tendon_compliance>true");
  EXPECT_NE(import_error(rigid).find("muscle 'RightMuscle': ignore_tendon_compliance = true is not supported"), std::string::npos)
      << import_error(rigid);
  const std::string partial =
      replaced(tug, "<stiffness_at_one_norm_force></stiffness_at_one_norm_force>", "<stiffness_at_one_norm_force>30</stiffness_at_one_norm_force>");
  EXPECT_NE(import_error(partial).find("muscle 'RightMuscle': OpenSim FiberForceLengthCurve: its optional properties must be all set"),
            std::string::npos)
      << import_error(partial);
  const std::string flat_fv = replaced(tug, "<concentric_slope_near_vmax>0.25", "<concentric_slope_near_vmax>0");
  EXPECT_NE(import_error(flat_fv).find("concentric_slope_near_vmax"), std::string::npos) << import_error(flat_fv);
  EXPECT_NE(import_error(flat_fv).find("muscle 'RightMuscle'"), std::string::npos) << import_error(flat_fv);

  const std::string noted_text = replaced(
      replaced(tug, "<ignore_activation_dynamics>false", "<ignore_activation_dynamics>true"),
      "<deactivation_time_constant>0.040000000000000001</deactivation_time_constant>",
      "<deactivation_time_constant>0.040000000000000001</deactivation_time_constant><minimum_activation>0</minimum_activation>");
  const fp::OpenSimImport noted = import_text(noted_text);
  std::string notes;
  for (const auto& n : noted.notes) notes += n + "\n";
  EXPECT_NE(notes.find("muscle 'LeftMuscle': minimum_activation 0 read as 0.0001"), std::string::npos) << notes;
  EXPECT_NE(notes.find("muscle 'LeftMuscle': ignore_activation_dynamics = true read as false"), std::string::npos) << notes;
  EXPECT_EQ(noted.model.muscles[0].parameters.activation_floor, 1e-4);
}

// fiber_damping 0: OpenSim's undamped model, whose curves OpenSim adjusts (fL at least 0.1, each
// fV slope at vmax at least half its slope near vmax: 0.125 concentric, 0.075 eccentric).
TEST(MillardImport, AnUndampedMuscleHasOpenSimsUndampedCurves) {
  const std::string osim = replaced(file_text(kTug), "<deactivation_time_constant>0.040000000000000001</deactivation_time_constant>",
                                    "<deactivation_time_constant>0.04</deactivation_time_constant><fiber_damping>0</fiber_damping>");
  const fp::ModelDescription model = import_text(osim).model;
  const fm::MuscleParameters& p = model.muscles[0].parameters;
  EXPECT_FALSE(millard(p).damped());
  EXPECT_EQ(p.fiber_damping, 0.0);
  const fm::Millard2012Curves& curves = millard(p).curves();
  EXPECT_NEAR(curves.active_force_length.evaluate(0.3).value, 0.1, 1e-15);
  EXPECT_NEAR(curves.force_velocity.evaluate(-1.0).first, 0.125, 1e-12);
  EXPECT_NEAR(curves.force_velocity.evaluate(1.0).first, 0.075, 1e-12);
  const std::string negative = replaced(file_text(kTug), "<deactivation_time_constant>0.040000000000000001</deactivation_time_constant>",
                                        "<deactivation_time_constant>0.04</deactivation_time_constant><minimum_activation>-0.1</minimum_activation>");
  EXPECT_NE(import_error(negative).find("muscle 'RightMuscle': minimum_activation = -0.1000 must be >= 0"), std::string::npos)
      << import_error(negative);
}

// ---- model files -------------------------------------------------------------------------

// A slider with two Millard muscles: one with its own curves (damped), one undamped with
// OpenSim's default curves.
json millard_model_json() {
  return json::parse(R"({
    "bodies": [{"name": "block", "mass_kg": 20, "mass_center_m": [0, 0, 0], "inertia_about_mass_center_kg_m2": 0.1}],
    "joints": [{"name": "rail", "type": "slider", "parent": "ground", "child": "block", "location_in_parent_m": [0, 0, 0],
                "axis": [1, 0, 0], "range_m": [-0.05, 0.05]}],
    "muscles": [
      {"name": "right", "max_isometric_force_N": 1000, "optimal_fiber_length_m": 0.1, "tendon_slack_length_m": 0.2,
       "length_at_zero_angles_m": 0.3, "moment_arms_m": {"rail": -1}, "muscle_model": "millard2012", "fiber_damping": 0.05,
       "maximum_pennation_angle_rad": 1.2,
       "millard2012_curves": {"active_force_length": {"min_norm_active_fiber_length": 0.5},
                              "force_velocity": {"concentric_slope_near_vmax": 0.2},
                              "tendon_force_length": {"strain_at_one_norm_force": 0.04}}},
      {"name": "left", "max_isometric_force_N": 1000, "optimal_fiber_length_m": 0.1, "tendon_slack_length_m": 0.2,
       "length_at_zero_angles_m": 0.3, "moment_arms_m": {"rail": 1}, "muscle_model": "millard2012", "fiber_damping": 0}]})");
}

TEST(MillardModelFile, CurvesAreReadWithOpenSimsDefaultsForTheRest) {
  const fp::ModelDescription model = fp::parse_model_json(millard_model_json().dump(), "millard.json");
  fm::Millard2012CurveParameters c;  // OpenSim's defaults, adjusted to damped by hand
  c.active_force_length.min_norm_active_fiber_length = 0.5;
  c.active_force_length.minimum_value = 0.0;
  c.force_velocity.concentric_slope_near_vmax = 0.2;
  c.tendon_force_length.strain_at_one_norm_force = 0.04;
  const fm::MuscleParameters& right = model.muscles[0].parameters;
  expect_same_curves(millard(right).curves(), fm::millard2012_curves(c), "right");
  EXPECT_EQ(right.tendon_strain_at_max_force, 0.04);  // follows the curve
  EXPECT_EQ(millard(right).maximumPennationAngle(), 1.2);
  const fm::MuscleParameters& left = model.muscles[1].parameters;
  EXPECT_FALSE(millard(left).damped());
  EXPECT_EQ(left.fiber_damping, 0.0);
  // Undamped: fL's floor is 0.1, and each fV slope at vmax half its slope near it.
  EXPECT_NEAR(millard(left).curves().active_force_length.evaluate(0.3).value, 0.1, 1e-15);
  EXPECT_NEAR(millard(left).curves().force_velocity.evaluate(-1.0).first, 0.125, 1e-12);
}

TEST(MillardModelFile, WritingAndReadingGivesTheSameCurves) {
  const fp::ModelDescription model = fp::parse_model_json(millard_model_json().dump(), "millard.json");
  const std::string text = fp::model_json_text(model);
  const fp::ModelDescription back = fp::parse_model_json(text, "round_trip.json");
  EXPECT_EQ(fp::model_json_text(back), text);
  for (std::size_t k = 0; k < 2; ++k) {
    const fm::MuscleParameters &a = model.muscles[k].parameters, &b = back.muscles[k].parameters;
    expect_same_curves(millard(a).curves(), millard(b).curves(), a.name);
    EXPECT_EQ(millard(a).damped(), millard(b).damped());
    EXPECT_EQ(millard(a).maximumPennationAngle(), millard(b).maximumPennationAngle());
    EXPECT_EQ(a.fiber_damping, b.fiber_damping);
    EXPECT_EQ(a.tendon_strain_at_max_force, b.tendon_strain_at_max_force);
  }
  // The default undamped muscle writes no curves; the other only those it changes.
  const json written = json::parse(text);
  EXPECT_FALSE(written["muscles"][1].contains("millard2012_curves"));
  EXPECT_EQ(written["muscles"][0]["millard2012_curves"].size(), 3u);
  // An imported model too (the Tug of War's own curves).
  const fp::ModelDescription tug = import_text(non_default_tug()).model;
  const fp::ModelDescription tug_back = fp::parse_model_json(fp::model_json_text(tug), "tug.json");
  for (std::size_t k = 0; k < 2; ++k)
    expect_same_curves(millard(tug.muscles[k].parameters).curves(), millard(tug_back.muscles[k].parameters).curves(), "tug");
}

TEST(MillardModelFile, BadCurveFieldsAreNamed) {
  auto error = [](const std::function<void(json&)>& spoil) {
    json j = millard_model_json();
    spoil(j);
    try {
      fp::parse_model_json(j.dump(), "bad.json");
    } catch (const fp::ModelFileError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  auto expect = [&](const std::function<void(json&)>& spoil, const std::string& words) {
    const std::string e = error(spoil);
    EXPECT_NE(e.find(words), std::string::npos) << e;
  };
  json& (*curves)(json&) = [](json& j) -> json& { return j["muscles"][0]["millard2012_curves"]; };
  expect([&](json& j) { curves(j)["active_force_length"]["min_norm_active_fiber_length"] = "half"; },
         "muscles[0].millard2012_curves.active_force_length.min_norm_active_fiber_length: must be a number");
  expect([&](json& j) { curves(j)["active_force_lenght"] = json::object(); },
         "muscles[0].millard2012_curves.active_force_lenght: unknown curve");
  expect([&](json& j) { curves(j)["force_velocity"]["slope"] = 1; }, "muscles[0].millard2012_curves.force_velocity.slope: unknown property");
  expect([&](json& j) { curves(j)["tendon_force_length"] = 0.04; },
         "muscles[0].millard2012_curves.tendon_force_length: must be an object");
  expect([&](json& j) { curves(j)["tendon_force_length"]["strain_at_one_norm_force"] = -0.04; },
         "muscles[0].millard2012_curves: OpenSim TendonForceLengthCurve: strain_at_one_norm_force");
  expect([&](json& j) { curves(j)["fiber_force_length"]["curviness"] = 0.5; },
         "muscles[0].millard2012_curves: OpenSim FiberForceLengthCurve: its optional properties must be all set");
  expect([&](json& j) { j["muscles"][0]["maximum_pennation_angle_rad"] = 2.0; }, "muscles[0].maximum_pennation_angle_rad:");
  expect([&](json& j) { j["muscles"][0]["muscle_model"] = "thelen2003"; },
         "muscles[0].millard2012_curves: only for a muscle whose muscle_model is \"millard2012\"");
  // The strain stated beside a curve must be the curve's own.
  expect([&](json& j) { j["muscles"][0]["tendon_strain_at_max_force"] = 0.05; }, "tendon_strain_at_max_force");
}

}  // namespace
