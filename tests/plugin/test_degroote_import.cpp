// An .osim's muscles replaced by DeGroote-Fregly 2016 muscles as OpenSim Moco's
// ModOpReplaceMusclesWithDeGrooteFregly2016 (DeGrooteFregly2016Muscle::replaceMuscles) maps
// them, and their passive force ignored as ModOpIgnorePassiveFiberForcesDGF does: each field
// against the same file's plain import, on arm26 (Thelen muscles) and the tug of war (Millard
// muscles); contradictory options refused by name.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"

#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/muscles/muscle_model.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"

namespace fp = flatsos::plugin;
namespace fm = flatsos::muscles;

namespace {

const std::string kArm26 = std::string(FLATSOS_SOURCE_DIR) + "/models/opensim/arm26/arm26.osim";
const std::string kTug = std::string(FLATSOS_SOURCE_DIR) + "/models/opensim/Tug_of_War_Millard.osim";

fp::ModelDescription import(const std::string& file, bool degroote, bool ignore_passive = false) {
  fp::OpenSimFileOptions o;
  o.degroote_fregly2016_muscles = degroote;
  o.ignore_passive_fiber_forces = ignore_passive;
  return fp::import_opensim_file(file, o).model;
}

// What Moco copies from every muscle.
void expect_common_fields(const fm::MuscleParameters& replaced, const fm::MuscleParameters& original) {
  EXPECT_EQ(replaced.model->name(), "degroote_fregly2016") << original.name;
  EXPECT_TRUE(replaced.model->slopeJumps().empty());
  EXPECT_EQ(replaced.name, original.name);
  EXPECT_EQ(replaced.max_isometric_force_N, original.max_isometric_force_N);
  EXPECT_EQ(replaced.optimal_fiber_length_m, original.optimal_fiber_length_m);
  EXPECT_EQ(replaced.tendon_slack_length_m, original.tendon_slack_length_m);
  EXPECT_EQ(replaced.pennation_angle_at_optimal_rad, original.pennation_angle_at_optimal_rad);
  EXPECT_EQ(replaced.max_shortening_velocity_in_optimal_lengths_per_s,
            original.max_shortening_velocity_in_optimal_lengths_per_s);
  EXPECT_EQ(replaced.activation_time_constant_s, original.activation_time_constant_s);
  EXPECT_EQ(replaced.deactivation_time_constant_s, original.deactivation_time_constant_s);
}

}  // namespace

TEST(DeGrooteImport, Arm26sThelenMusclesBecomeDeGrooteFreglysAsMocoMapsThem) {
  const fp::ModelDescription thelen = import(kArm26, false), degroote = import(kArm26, true);
  ASSERT_EQ(degroote.numMuscles(), thelen.numMuscles());
  for (int j = 0; j < thelen.numMuscles(); ++j) {
    const fm::MuscleParameters &r = degroote.muscles[j].parameters, &o = thelen.muscles[j].parameters;
    ASSERT_EQ(o.model->name(), "thelen2003");
    expect_common_fields(r, o);
    // Thelen's FmaxTendonStrain and FmaxMuscleStrain (arm26 states 0.033 and 0.6), no damping.
    EXPECT_EQ(r.tendon_strain_at_max_force, o.tendon_strain_at_max_force);
    EXPECT_EQ(r.tendon_strain_at_max_force, 0.033);
    EXPECT_EQ(r.passive_fiber_strain_at_one_norm_force, o.passive_fiber_strain_at_one_norm_force);
    EXPECT_EQ(r.fiber_damping, 0.0);
    // DeGroote-Fregly's own laws: Fmax at the tendon strain e0, a passive force at 1.5 Lopt.
    const double e0_length = r.tendon_slack_length_m * (1.0 + r.tendon_strain_at_max_force);
    EXPECT_NEAR(fm::tendon_force(r, e0_length), r.max_isometric_force_N, 1e-9 * r.max_isometric_force_N);
    EXPECT_GT(r.model->passiveFiberForce(r, 1.5 * r.optimal_fiber_length_m).value, 0.0);
  }
  const auto provenance = nlohmann::json::parse(degroote.provenance_json);
  EXPECT_TRUE(provenance.contains("degroote_fregly2016_muscles"));
}

TEST(DeGrooteImport, IgnoringPassiveFiberForcesLeavesThemOut) {
  const fp::ModelDescription model = import(kArm26, true, true);
  for (const auto& m : model.muscles) {
    const fm::MuscleParameters& p = m.parameters;
    EXPECT_EQ(p.passive_fiber_strain_at_one_norm_force, 0.0);
    EXPECT_FALSE(p.hasPassiveFiberForce()) << p.name;
    EXPECT_EQ(p.model->passiveFiberForce(p, 1.5 * p.optimal_fiber_length_m).value, 0.0);
  }
  const auto provenance = nlohmann::json::parse(model.provenance_json);
  EXPECT_NE(provenance["degroote_fregly2016_muscles"].get<std::string>().find("passive"), std::string::npos);
}

TEST(DeGrooteImport, MillardMusclesGiveTheirCurvesStrainsAndDamping) {
  const fp::ModelDescription millard = import(kTug, false), degroote = import(kTug, true);
  ASSERT_EQ(degroote.numMuscles(), 2);
  for (int j = 0; j < 2; ++j) {
    const fm::MuscleParameters &r = degroote.muscles[j].parameters, &o = millard.muscles[j].parameters;
    ASSERT_EQ(o.model->name(), "millard2012");
    expect_common_fields(r, o);
    EXPECT_EQ(r.tendon_strain_at_max_force, 0.049);             // TendonForceLengthCurve's (OpenSim's default)
    EXPECT_EQ(r.passive_fiber_strain_at_one_norm_force, 0.6);   // FiberForceLengthCurve's, as the file states
    EXPECT_EQ(r.fiber_damping, 0.1);                            // Millard's fiber_damping (OpenSim's default)
  }
}

TEST(DeGrooteImport, ContradictoryOptionsAreRefusedByName) {
  fp::OpenSimFileOptions both;
  both.opensim_2_muscles = true;
  both.degroote_fregly2016_muscles = true;
  try {
    fp::import_opensim_file(kArm26, both);
    FAIL() << "accepted OpenSim 2.x's and DeGroote-Fregly's muscles at once";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("opensim_2_muscles and degroote_fregly2016_muscles"), std::string::npos) << e.what();
  }
  fp::OpenSimFileOptions passive_only;
  passive_only.ignore_passive_fiber_forces = true;
  try {
    fp::import_opensim_file(kArm26, passive_only);
    FAIL() << "ignored passive forces of muscles that are not DeGroote-Fregly's";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("ignore_passive_fiber_forces"), std::string::npos) << e.what();
  }
}
