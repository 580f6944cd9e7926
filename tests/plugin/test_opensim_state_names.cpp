// The states flatsos writes for an imported OpenSim model name OpenSim 4's state variables
// (/jointset/<joint>/<coordinate>/value and /speed, /forceset/<muscle>/activation and
// /fiber_length, the names read from the .osim itself), and they read back (as OpenSim's forward
// tool takes a first row: --initial-states) into the same state.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"

#include <string>

#include <gtest/gtest.h>

#include "flatsos/plugin/io/initial_states.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"
#include "flatsos/plugin/io/opensim_model.hpp"
#include "flatsos/plugin/io/state_table.hpp"

namespace fp = flatsos::plugin;

namespace {

const std::string kArm26 = std::string(FLATSOS_SOURCE_DIR) + "/models/opensim/arm26/arm26.osim";

TEST(OpenSimStateNames, ImportedArm26sStatesNameOpenSimsStateVariables) {
  const fp::OpenSimModel osim = fp::read_opensim_model(kArm26);
  const fp::MusculoskeletalModel model(fp::import_opensim_file(kArm26).model);
  const fp::StoTable table = fp::make_state_table(model);
  for (const fp::OpenSimCoordinate& c : osim.coordinates)
    for (const char* kind : {"/value", "/speed"}) {
      const std::string column = "/jointset/" + c.joint + "/" + c.name + kind;
      EXPECT_GE(table.columnIndex(column), 0) << column;
    }
  for (const auto& m : model.description().muscles)
    for (const char* kind : {"/activation", "/fiber_length"}) {
      const std::string column = "/forceset/" + m.parameters.name + kind;
      EXPECT_GE(table.columnIndex(column), 0) << column;
    }
  EXPECT_EQ(model.description().numMuscles(), 6);
}

TEST(OpenSimStateNames, WrittenStatesReadBackIntoTheSameState) {
  const fp::MusculoskeletalModel model(fp::import_opensim_file(kArm26).model);
  SimTK::State s = model.defaultState();
  model.setJointAngles(s, Eigen::Vector2d(0.1, 1.2));
  model.setJointSpeeds(s, Eigen::Vector2d(-0.3, 0.7));
  Eigen::VectorXd a(6);
  a << 0.05, 0.2, 0.35, 0.5, 0.65, 0.8;
  model.setActivations(s, a);
  model.setTendonLengths(s, model.tendonLengths(s) * 1.003);
  fp::StoTable table = fp::make_state_table(model);
  fp::append_state_row(model, s, table);
  SimTK::State back = model.defaultState();
  EXPECT_TRUE(fp::set_initial_states(model, back, table, "written").empty());
  EXPECT_LT((model.jointAngles(back) - model.jointAngles(s)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((model.jointSpeeds(back) - model.jointSpeeds(s)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((model.activations(back) - a).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((model.tendonLengths(back) - model.tendonLengths(s)).cwiseAbs().maxCoeff(), 1e-12);
}

}  // namespace
