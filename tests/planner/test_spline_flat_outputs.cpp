// Flat outputs as clamped B-splines in the SOS program: the paper's quartic is the one-span case;
// refining the knots (nested spaces, same constraints) never raises the optimum; the reported
// cost is the integral of the flat outputs; the boundary conditions hold; spans that do not line
// up with the torque pieces stay sound and certified; and a rich plan is within 1 % above an
// independent dense-grid bound (exact torques, no torque model, no exchange: a relaxation).
#include <gtest/gtest.h>

#include "flatsos/planner/numerics/simplex_lp.hpp"
#include "scenario_fixture.hpp"

namespace fpl = flatsos::planner;

namespace {

class SplineFlatOutputs : public ::testing::Test {
 protected:
  flatsos::test::ArmPlanning arm;
  fpl::MuscleState s0 = flatsos::test::open_loop_initial_state(*arm.model);
  fpl::OpenLoopOptions options = flatsos::test::open_loop_options();

  fpl::OpenLoopPlan plan(int degree, int spans, int pieces = 12) const {
    auto o = options;
    o.sos.flat_output_degree = degree;
    o.sos.flat_output_spans = spans;
    o.torque.pieces = pieces;
    return fpl::plan_open_loop(arm.flat, s0, o);
  }
};

// All B-spline coefficients as variables, the boundary conditions as equality rows, and the
// reserves only at `points` grid times with the exact inverse-dynamics torque.
double dense_grid_lower_bound(const fpl::FlatOutputMap& flat, const fpl::OpenLoopPlan& plan, const fpl::MuscleState& s0,
                              double reserve, int points) {
  const fpl::BSplineBasis& basis = plan.Y->basis();
  const double T = basis.duration();
  const int p = flat.numFlatOutputs(), m = flat.numMuscles(), size = basis.size(), nv = p * size;
  const fpl::FlatState y0 = flat.forward(s0);
  std::vector<Eigen::RowVectorXd> rows;
  std::vector<double> lo, hi;
  auto add = [&](const Eigen::RowVectorXd& r, double l, double h) { rows.push_back(r), lo.push_back(l), hi.push_back(h); };
  for (int l = 0; l < p; ++l) {
    for (int order = 0; order < 2; ++order) {
      Eigen::RowVectorXd r = Eigen::RowVectorXd::Zero(nv);
      r.segment(l * size, size) = basis.derivativeRow(0.0, order);
      add(r, y0.Y(l, order), y0.Y(l, order));
    }
    for (int order = 1; order < 3; ++order) {
      Eigen::RowVectorXd r = Eigen::RowVectorXd::Zero(nv);
      r.segment(l * size, size) = basis.derivativeRow(T, order);
      add(r, 0.0, 0.0);
    }
  }
  for (int i = 0; i < points; ++i) {
    const double t = T * i / (points - 1);
    const fpl::Jet j = plan.path.jet(t, 3);
    const Eigen::VectorXd tau = flat.torque(j.col(0), j.col(1), j.col(2));
    for (int k = 0; k < m; ++k) {
      Eigen::RowVectorXd r = Eigen::RowVectorXd::Zero(nv);
      for (int l = 0; l < p; ++l) r.segment(l * size, size) = flat.CY()(k, l) * basis.derivativeRow(t, 0);
      add(r, reserve - flat.Ctau().row(k).dot(tau), 1e19);
    }
  }
  // Cost weights by a fine trapezoid rule of each basis function (independent of the SOS setup's
  // per-segment power integrals).
  Eigen::RowVectorXd integral = Eigen::RowVectorXd::Zero(size);
  const int quad = 24000;
  for (int i = 0; i <= quad; ++i) integral += (i == 0 || i == quad ? 0.5 : 1.0) * T / quad * basis.derivativeRow(T * i / quad, 0);
  fpl::LinearProgram lp;
  lp.cost.resize(nv);
  for (int l = 0; l < p; ++l) lp.cost.segment(l * size, size) = integral.transpose();
  lp.G.resize(static_cast<Eigen::Index>(rows.size()), nv);
  for (std::size_t r = 0; r < rows.size(); ++r) lp.G.row(static_cast<Eigen::Index>(r)) = rows[r];
  lp.row_lower = Eigen::Map<Eigen::VectorXd>(lo.data(), static_cast<Eigen::Index>(lo.size()));
  lp.row_upper = Eigen::Map<Eigen::VectorXd>(hi.data(), static_cast<Eigen::Index>(hi.size()));
  lp.x_lower = Eigen::VectorXd::Constant(nv, -1e6);
  lp.x_upper = Eigen::VectorXd::Constant(nv, 1e6);
  const auto r = fpl::solve_linear_program_simplex(lp);
  EXPECT_EQ(r.status, fpl::SolveStatus::Solved) << r.solver_status;
  return r.objective;
}

}  // namespace

TEST_F(SplineFlatOutputs, OneSpanQuarticIsThePapersFormulation) {
  const auto quartic = plan(4, 1);
  ASSERT_EQ(quartic.status, fpl::SolveStatus::Solved) << quartic.message;
  EXPECT_NEAR(quartic.sos.cost_N_s, 958.32, 0.01);
  EXPECT_TRUE(quartic.sos.certified);
}

TEST_F(SplineFlatOutputs, RefinedKnotsNeverRaiseTheOptimum) {
  // Cubic splines on 3, 6 and 12 spans are nested (each knot vector refines the last), and with
  // 12 torque pieces the constraint segments are the same: the optimum can only go down.
  double previous = 1e300;
  for (int spans : {3, 6, 12}) {
    const auto p = plan(3, spans);
    ASSERT_EQ(p.status, fpl::SolveStatus::Solved) << spans << " spans: " << p.message;
    EXPECT_LE(p.sos.cost_N_s, previous + 1e-6 * previous) << spans << " spans";
    previous = p.sos.cost_N_s;
  }
  // Quartics on 1, 2 and 4 spans too, starting from the paper's.
  previous = 1e300;
  for (int spans : {1, 2, 4}) {
    const auto p = plan(4, spans);
    ASSERT_EQ(p.status, fpl::SolveStatus::Solved) << spans << " spans: " << p.message;
    EXPECT_LE(p.sos.cost_N_s, previous + 1e-6 * previous) << spans << " spans";
    previous = p.sos.cost_N_s;
  }
  EXPECT_LT(previous, 0.7 * 958.32);  // the basis, not the method, limited the paper's effort
}

TEST_F(SplineFlatOutputs, CostIsTheIntegralOfTheFlatOutputsAndBoundaryConditionsHold) {
  const auto p = plan(3, 12);
  ASSERT_EQ(p.status, fpl::SolveStatus::Solved) << p.message;
  // Simpson's rule is exact for cubics; 3000 intervals put 250 (an even number) in each span.
  const int intervals = 3000;
  const double h = 3.0 / intervals;
  double integral = 0.0;
  for (int i = 0; i <= intervals; ++i) {
    const double w = (i == 0 || i == intervals) ? 1.0 : (i % 2 ? 4.0 : 2.0);
    integral += w * h / 3.0 * p.Y->jet(i * h, 1).sum();
  }
  EXPECT_NEAR(p.sos.cost_N_s, integral, 1e-9 * integral);
  const fpl::FlatState y0 = arm.flat.forward(s0);
  const Eigen::MatrixXd start = p.Y->jet(0.0, 2), end = p.Y->jet(3.0, 3);
  EXPECT_LT((start - y0.Y).cwiseAbs().maxCoeff(), 1e-9 * (1.0 + y0.Y.cwiseAbs().maxCoeff()));
  EXPECT_LT(end.rightCols(2).cwiseAbs().maxCoeff(), 1e-9);
}

TEST_F(SplineFlatOutputs, SpansThatCutTorquePiecesStaySoundAndCertified) {
  // 5 spans against 12 torque pieces: most segments are shorter than both.
  const auto p = plan(3, 5);
  ASSERT_EQ(p.status, fpl::SolveStatus::Solved) << p.message;
  EXPECT_TRUE(p.sos.certified) << p.sos.certified_pieces << " of " << p.sos.near_active_pieces;
  EXPECT_GE(p.sos.min_constraint_value_N, -1e-9);
  {
    auto ws = arm.flat.makeWorkspace();
    const fpl::PlanCheck dense = fpl::check_plan(arm.flat, ws, p.path, *p.Y, options.reserves_N, 3001);
    EXPECT_GE(dense.min_reserve_margin_N, -1e-6);
  }
}

TEST_F(SplineFlatOutputs, RichPlanIsWithinOnePercentAboveAnIndependentDenseGridBound) {
  const auto p = plan(3, 12);
  ASSERT_EQ(p.status, fpl::SolveStatus::Solved) << p.message;
  const double bound = dense_grid_lower_bound(arm.flat, p, s0, 10.0, 1201);
  EXPECT_LE(bound, p.sos.cost_N_s * (1 + 1e-9));
  EXPECT_LT(p.sos.cost_N_s, 1.01 * bound) << "plan " << p.sos.cost_N_s << " bound " << bound;
}
