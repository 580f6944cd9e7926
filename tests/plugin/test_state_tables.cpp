// The tables a simulation writes are the ones OpenSim reads: coordinates by their paths
// (/jointset/<joint>/<coordinate>/value, /speed), controls apart (/forceset/<muscle>); a
// controls file read back as excitations reproduces the simulation (round trip).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "arm_fixture.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"
#include "flatsos/plugin/io/excitation_file.hpp"
#include "flatsos/plugin/io/state_table.hpp"

namespace fp = flatsos::plugin;

namespace {
std::shared_ptr<const fp::MusculoskeletalModel> elbow() {
  return fp::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) + "/models/elbow_1dof.json");
}

// Excitations rising linearly from 0.05 to 0.35 in 0.2 s, then held.
std::vector<std::shared_ptr<const fp::ExcitationSignal>> ramps(int m) {
  std::vector<std::shared_ptr<const fp::ExcitationSignal>> out;
  for (int j = 0; j < m; ++j)
    out.push_back(std::make_shared<fp::PiecewiseLinearSignal>(std::vector<double>{0.0, 0.2},
                                                              std::vector<double>{0.05, 0.35 - 0.1 * j}));
  return out;
}

fp::SimulationResult simulate_with(const fp::MusculoskeletalModel& model,
                                   const std::vector<std::shared_ptr<const fp::ExcitationSignal>>& signals) {
  SimTK::State s = model.defaultState();
  model.setJointAngles(s, Eigen::VectorXd::Constant(1, 0.3));
  fp::equilibrate_tendons(model, s, Eigen::VectorXd::Constant(model.numMuscles(), 0.05));
  for (int j = 0; j < model.numMuscles(); ++j) model.muscle(j).setExcitationSignal(s, signals[j]);
  fp::SimulationOptions o;
  o.duration_s = 0.3;
  o.report_interval_s = 0.01;
  o.accuracy = 1e-9;
  return fp::simulate(model, s, o);
}
}  // namespace

TEST(StateTables, CoordinatesByTheirOpenSimPathsAndControlsApart) {
  const auto model = elbow();
  const auto r = simulate_with(*model, ramps(3));
  ASSERT_TRUE(r.finite) << r.message;
  EXPECT_EQ(r.states.columns[1], "/jointset/elbow/elbow_flexion/value");
  EXPECT_EQ(r.states.columns[2], "/jointset/elbow/elbow_flexion/speed");
  EXPECT_EQ(fp::coordinate_value_column(*model, 0), r.states.columns[1]);
  for (const auto& c : r.states.columns) EXPECT_EQ(c.find("excitation"), std::string::npos) << c;
  EXPECT_EQ(r.controls.columns, (std::vector<std::string>{"time", "/forceset/biceps", "/forceset/brachialis", "/forceset/triceps"}));
  ASSERT_EQ(r.controls.rows.size(), r.states.rows.size());
  for (std::size_t k = 0; k < r.controls.rows.size(); ++k) {
    const double t = r.controls.rows[k][0];
    EXPECT_EQ(t, r.states.rows[k][0]);
    EXPECT_NEAR(r.controls.rows[k][1], 0.05 + 0.3 * std::min(t, 0.2) / 0.2, 1e-12) << "t = " << t;
  }
  // The coordinate name defaults to the joint's.
  EXPECT_EQ(fp::coordinate_value_column(*flatsos::test::load_arm(), 1), "/jointset/elbow/elbow/value");
}

TEST(StateTables, AControlsFileReadBackReproducesTheSimulation) {
  const auto model = elbow();
  const auto first = simulate_with(*model, ramps(3));
  const auto dir = std::filesystem::temp_directory_path() / ("flatsos_controls_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "controls.sto").string();
  fp::write_sto(file, first.controls);
  std::vector<std::string> names;
  for (const auto& m : model->description().muscles) names.push_back(m.parameters.name);
  const auto second = simulate_with(*model, fp::read_excitation_file(file, names));
  std::filesystem::remove_all(dir);
  ASSERT_EQ(second.states.rows.size(), first.states.rows.size());
  // The 0.01 s samples hold the ramp's corner at 0.2 s exactly: the same inputs, the same motion.
  for (std::size_t k = 0; k < first.states.rows.size(); ++k)
    for (std::size_t c = 0; c < first.states.columns.size(); ++c)
      EXPECT_NEAR(second.states.rows[k][c], first.states.rows[k][c], 1e-9 * (1.0 + std::abs(first.states.rows[k][c])))
          << first.states.columns[c] << " at row " << k;
}
