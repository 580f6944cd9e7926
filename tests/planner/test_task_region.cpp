// Flat outputs for a task (task_region.hpp): the region a task visits is the box its postures
// span widened by the margin and clipped to the joint ranges; OpenSim's arm26, whose ranges no E
// serves, gets an E that satisfies Assumption 1 over the task's region (checked independently:
// C_Y(q) 1 by a QR solve at grid and random postures there); a model whose E serves its ranges
// keeps it; a region outside the ranges is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "flatsos/planner/task_region.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;

namespace {

constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;

std::shared_ptr<const fp::MusculoskeletalModel> arm26() {
  static const auto model = std::make_shared<const fp::MusculoskeletalModel>(
      fp::import_opensim_file(std::string(FLATSOS_SOURCE_DIR) + "/models/opensim/arm26/arm26.osim").model);
  return model;
}

Eigen::VectorXd deg(double shoulder, double elbow) { return Eigen::Vector2d(shoulder, elbow) * kRadPerDeg; }

// The smallest entry of C_Y(q) 1 (R v = 0, E v = 1, by pivoted QR; -inf where C is singular).
double unit_force_margin(const fp::MusculoskeletalModel& model, const Eigen::MatrixXd& E, const Eigen::VectorXd& q) {
  const Eigen::MatrixXd R = model.momentArmMatrix(q);
  Eigen::MatrixXd C(R.cols(), R.cols());
  C << R, E;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(R.cols());
  rhs.tail(E.rows()).setOnes();
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(C);
  if (qr.rank() < C.rows()) return -INFINITY;
  return qr.solve(rhs).minCoeff();
}

TEST(TaskRegion, IsThePosturesSpanWidenedByTheMarginAndClippedToTheRanges) {
  const fp::ModelDescription& d = arm26()->description();
  const fp::JointRanges box = fpl::task_region(d, {deg(0, 15), deg(5, 90)});
  ASSERT_EQ(box.size(), 2u);
  EXPECT_NEAR(box[0][0], -10 * kRadPerDeg, 1e-12);
  EXPECT_NEAR(box[0][1], 15 * kRadPerDeg, 1e-12);
  EXPECT_NEAR(box[1][0], 5 * kRadPerDeg, 1e-12);
  EXPECT_NEAR(box[1][1], 100 * kRadPerDeg, 1e-12);
  // The elbow's range ends at 0 deg in arm26: a task starting at 5 deg is clipped there.
  const fp::JointRanges clipped = fpl::task_region(d, {deg(0, 5), deg(0, 60)});
  EXPECT_EQ(clipped[1][0], d.joints[1].range_rad[0]);
  EXPECT_THROW(fpl::task_region(d, {Eigen::VectorXd::Zero(3)}), std::invalid_argument);
  EXPECT_THROW(fpl::task_region(d, {deg(0, NAN)}), std::invalid_argument);
  EXPECT_THROW(fpl::task_region(d, {}), std::invalid_argument);
}

TEST(TaskRegion, Arm26GetsFlatOutputsThatHoldOverTheTasksRegion) {
  const auto model = arm26();
  EXPECT_THROW(fpl::FlatOutputMap{model}, fpl::FlatnessError);  // no E serves OpenSim's (narrowed) ranges
  const std::vector<Eigen::VectorXd> task = {deg(0, 15), deg(0, 90)};
  const fpl::FlatOutputMap flat = fpl::flat_outputs_for_task(model, task);
  const fp::JointRanges& region = flat.flatOutputs().region;
  ASSERT_EQ(region, fpl::task_region(model->description(), task));
  double smallest = INFINITY;
  for (int i = 0; i <= 20; ++i)
    for (int k = 0; k <= 20; ++k) {
      const Eigen::Vector2d q(region[0][0] + (region[0][1] - region[0][0]) * i / 20.0,
                              region[1][0] + (region[1][1] - region[1][0]) * k / 20.0);
      smallest = std::min(smallest, unit_force_margin(*model, flat.E(), q));
    }
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int s = 0; s < 500; ++s) {
    const Eigen::Vector2d q(region[0][0] + (region[0][1] - region[0][0]) * unit(random),
                            region[1][0] + (region[1][1] - region[1][0]) * unit(random));
    smallest = std::min(smallest, unit_force_margin(*model, flat.E(), q));
  }
  EXPECT_GT(smallest, 0.0);
  EXPECT_NEAR(flat.flatOutputs().margin.margin, smallest, 0.05 * smallest + 1e-9);  // the library's grid agrees
}

TEST(TaskRegion, FlatOutputsThatServeTheRangesAreKept) {
  auto d = fp::load_model_file(std::string(FLATSOS_SOURCE_DIR) + "/models/elbow_posture_dependent.json");
  const auto model = std::make_shared<const fp::MusculoskeletalModel>(d);
  const Eigen::VectorXd q0 = Eigen::VectorXd::Constant(model->numJoints(), 0.5);
  const fpl::FlatOutputMap flat = fpl::flat_outputs_for_task(model, {q0, q0});
  EXPECT_TRUE(flat.flatOutputs().region.empty());
  EXPECT_EQ(flat.E(), fpl::FlatOutputMap(model).E());
}

TEST(TaskRegion, ARegionOutsideTheRangesIsRefused) {
  const auto model = arm26();
  const auto& range = model->description().joints[1].range_rad;
  fp::JointRanges beyond = {{-0.1, 0.1}, {range[0], range[1] + 0.1}};
  EXPECT_THROW(fpl::FlatOutputMap::overRegion(model, beyond), std::invalid_argument);
  EXPECT_THROW(fpl::FlatOutputMap::overRegion(model, {{-0.1, 0.1}}), std::invalid_argument);
  fp::JointRanges reversed = {{0.1, -0.1}, {0.5, 1.0}};
  EXPECT_THROW(fpl::FlatOutputMap::overRegion(model, reversed), std::invalid_argument);
}

}  // namespace
