// External disturbances on the joints (disturbance_file.hpp): each row's forces act from its
// time until the next row's, none before the first; the force reaches the multibody system as a
// generalized force (the Tug of War's block accelerates by F / m more); bad tables are refused
// naming the column or the problem.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"

#include <cmath>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "flatsos/plugin/force/excitation_signal.hpp"
#include "flatsos/plugin/io/disturbance_file.hpp"
#include "flatsos/plugin/io/model_file.hpp"

namespace fp = flatsos::plugin;

namespace {

const std::string kTug = std::string(FLATSOS_SOURCE_DIR) + "/models/opensim/Tug_of_War_Millard.osim";

std::string write_table(const std::string& name, const std::string& header_extra, const std::string& body) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << "push\nversion=1\n" << header_extra << "endheader\n" << body;
  return path;
}

TEST(PiecewiseConstantSignal, HoldsEachValueUntilTheNextTimeAndIsZeroBefore) {
  const fp::PiecewiseConstantSignal s({1.0, 2.0, 3.5}, {20.0, -5.0, 0.0});
  EXPECT_EQ(s.value(0.999), 0.0);
  EXPECT_EQ(s.value(1.0), 20.0);
  EXPECT_EQ(s.value(1.999), 20.0);
  EXPECT_EQ(s.value(2.0), -5.0);
  EXPECT_EQ(s.value(3.4), -5.0);
  EXPECT_EQ(s.value(100.0), 0.0);
  EXPECT_THROW(fp::PiecewiseConstantSignal({1.0, 1.0}, {0.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(fp::PiecewiseConstantSignal({1.0}, {NAN}), std::invalid_argument);
}

// The block's acceleration with and without a 20 N push at the same state: 20 N / its mass.
TEST(DisturbanceFile, APushAcceleratesTheTugOfWarsBlockByForceOverMass) {
  const fp::ModelDescription d = fp::load_model_file(kTug);
  const std::string file = write_table("tug_push.sto", "inDegrees=no\n", "time\tblock_tz\n0\t0\n0.5\t20\n");
  const auto torques = fp::read_disturbance_file(d, file);
  ASSERT_EQ(torques.size(), 1u);
  const fp::MusculoskeletalModel plain(d), pushed(d, torques);
  double mass_kg = 0.0;
  for (const auto& b : d.bodies) mass_kg += b.mass_kg;
  for (const double t : {0.25, 0.75}) {
    SimTK::State a = plain.defaultState(), b = pushed.defaultState();
    a.setTime(t);
    b.setTime(t);
    plain.system().realize(a, SimTK::Stage::Acceleration);
    pushed.system().realize(b, SimTK::Stage::Acceleration);
    EXPECT_NEAR(b.getUDot()[0] - a.getUDot()[0], t < 0.5 ? 0.0 : 20.0 / mass_kg, 1e-9) << "t = " << t;
  }
}

TEST(DisturbanceFile, BadTablesAreRefusedNamingTheProblem) {
  const fp::ModelDescription d = fp::load_model_file(kTug);
  try {
    fp::read_disturbance_file(d, write_table("bad_column.sto", "", "time\tknee\n0\t1\n"));
    FAIL() << "an unknown column was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'knee'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(fp::read_disturbance_file(d, write_table("degrees.sto", "inDegrees=yes\n", "time\tblock_tz\n0\t1\n")),
               std::invalid_argument);
  EXPECT_THROW(fp::read_disturbance_file(d, write_table("backwards.sto", "", "time\tblock_tz\n1\t1\n0\t2\n")),
               std::invalid_argument);
  EXPECT_THROW(fp::disturbance_torques(d, {0.0}, Eigen::MatrixXd::Zero(1, 2)), std::invalid_argument);
  EXPECT_THROW(fp::disturbance_torques(d, {0.0}, Eigen::MatrixXd::Constant(1, 1, NAN)), std::invalid_argument);
  EXPECT_TRUE(fp::disturbance_torques(d, {0.0}, Eigen::MatrixXd::Zero(1, 1)).empty());  // nothing pushes
}

}  // namespace
