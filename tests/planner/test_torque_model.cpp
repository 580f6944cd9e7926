// The torque model of the SOS program: on a dense grid the remainder bound holds on every piece;
// the first piece matches the torque and its rate that the initial state fixes, so its bound
// vanishes at t = 0; K = 1, r = 0 is the paper's box (midpoint, half range).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "flatsos/planner/joint_paths.hpp"
#include "flatsos/planner/numerics/bspline.hpp"
#include "flatsos/planner/torque_model.hpp"
#include "flatsos/planner/torque_model_study.hpp"
#include "scenario_fixture.hpp"

namespace fpl = flatsos::planner;

namespace {

struct TorqueModelScenario : ::testing::Test {
  flatsos::test::ArmPlanning arm;
  flatsos::plugin::ModelWorkspace ws = arm.model->makeWorkspace();
  fpl::JointPath path;
  void SetUp() override {
    const fpl::FlatState y0 = arm.flat.forward(flatsos::test::open_loop_initial_state(*arm.model));
    Eigen::MatrixXd terminal = Eigen::MatrixXd::Zero(2, 5);
    terminal(0, 0) = flatsos::test::deg(90);
    path = fpl::fit_joint_path(3.0, y0.q, terminal);
  }
  Eigen::VectorXd tau(double t) {
    const fpl::Jet j = path.jet(t, 3);
    return arm.flat.torque(ws, j.col(0), j.col(1), j.col(2));
  }
};

TEST_F(TorqueModelScenario, TheRemainderBoundHoldsOnADenseGridOfEveryPiece) {
  for (int degree : {1, 2, 3, 5}) {
    fpl::TorqueModelStudyOptions study;
    study.degree = degree;
    const fpl::TorqueModel model = fpl::build_torque_model(arm.flat, ws, path, {}, study);
    ASSERT_EQ(model.pieces.size(), 12u);
    for (const auto& piece : model.pieces)
      for (int i = 0; i <= 200; ++i) {
        const double s = i / 200.0;
        const Eigen::VectorXd exact = tau(piece.t0_s + s * (piece.t1_s - piece.t0_s));
        for (int joint = 0; joint < 2; ++joint)
          EXPECT_LE(std::abs(exact[joint] - piece.torque[joint](s)), piece.remainderAt(joint, s) + 1e-12)
              << "degree " << degree << ", piece at " << piece.t0_s << " s, s = " << s << ", joint " << joint;
      }
  }
}

TEST_F(TorqueModelScenario, PiecesThatGrowFollowTheirBreakpointsAndKeepTheBound) {
  fpl::TorqueModelOptions o;
  o.pieces = 10;
  o.piece_growth = 1.3;
  const fpl::TorqueModel model = fpl::build_torque_model(arm.flat, ws, path, o);
  const std::vector<double> breaks = fpl::geometric_breakpoints(10, 3.0, 1.3);
  ASSERT_EQ(model.pieces.size(), 10u);
  for (std::size_t k = 0; k < model.pieces.size(); ++k) {
    const auto& piece = model.pieces[k];
    EXPECT_EQ(piece.t0_s, breaks[k]);
    EXPECT_EQ(piece.t1_s, breaks[k + 1]);
    for (int i = 0; i <= 200; ++i) {
      const double s = i / 200.0;
      const Eigen::VectorXd exact = tau(piece.t0_s + s * (piece.t1_s - piece.t0_s));
      for (int joint = 0; joint < 2; ++joint)
        EXPECT_LE(std::abs(exact[joint] - piece.torque[joint](s)), piece.remainderAt(joint, s) + 1e-12)
            << "piece at " << piece.t0_s << " s, s = " << s << ", joint " << joint;
    }
  }
  // Short pieces where the torque changes: the first piece's bound is smaller than uniform's.
  const fpl::TorqueModel uniform = fpl::build_torque_model(arm.flat, ws, path, {10});
  EXPECT_LT(model.pieces[0].remainder_N_m.maxCoeff(), uniform.pieces[0].remainder_N_m.maxCoeff());
  for (double bad : {0.0, -1.0, std::nan("")}) {
    o.piece_growth = bad;
    EXPECT_THROW(fpl::build_torque_model(arm.flat, ws, path, o), std::invalid_argument) << bad;
  }
}

TEST_F(TorqueModelScenario, TheFirstPieceMatchesTheInitialTorqueAndRateSoItsBoundVanishesThere) {
  const fpl::TorqueModel model = fpl::build_torque_model(arm.flat, ws, path, {});
  const auto& first = model.pieces.front();
  const double h = first.t1_s - first.t0_s;
  const Eigen::MatrixXd jet0 = arm.flat.torqueJet(ws, path.jet(0.0, 5)).tau;
  EXPECT_EQ(first.remainder_order, 2);
  for (int joint = 0; joint < 2; ++joint) {
    EXPECT_NEAR(first.torque[joint](0.0), jet0(joint, 0), 1e-12);
    EXPECT_NEAR(first.torque[joint].derivativeAt(0.0, 1) / h, jet0(joint, 1), 1e-9);
    EXPECT_EQ(first.remainderAt(joint, 0.0), 0.0);
    EXPECT_GT(first.remainder_N_m[joint], 0.0);
  }
  for (std::size_t k = 1; k < model.pieces.size(); ++k) EXPECT_EQ(model.pieces[k].remainder_order, 0);
}

TEST_F(TorqueModelScenario, OnePieceOfDegreeZeroIsThePapersBox) {
  fpl::TorqueModelOptions o;
  o.pieces = 1;
  fpl::TorqueModelStudyOptions study;
  study.degree = 0;
  study.samples_per_piece = 301;
  const fpl::TorqueModel model = fpl::build_torque_model(arm.flat, ws, path, o, study);
  ASSERT_EQ(model.pieces.size(), 1u);
  const auto& box = model.pieces[0];
  EXPECT_EQ(box.remainder_order, 0);
  for (int joint = 0; joint < 2; ++joint) {
    double lo = 1e300, hi = -1e300;
    for (int i = 0; i < 301; ++i) {
      const double v = tau(3.0 * i / 300.0)[joint];
      lo = std::min(lo, v), hi = std::max(hi, v);
    }
    EXPECT_NEAR(box.torque[joint](0.5), 0.5 * (lo + hi), 1e-9);
    EXPECT_NEAR(box.remainder_N_m[joint], 0.5 * (hi - lo), 1e-9);
  }
}

}  // namespace
