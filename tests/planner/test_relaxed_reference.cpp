// Squared excitations on the paper's arm with the joint path free: where the flatness plan and
// the collocation reference differ, and why. Along the reference's own optimal joint path the
// flatness plan costs what the reference costs from 0.15 s on; the whole difference is in the
// first 0.15 s, where the reference's excitation switches between 0 and 1 from one collocation
// point to the next. Deactivation (40 ms) is slower than activation (10 ms), so the cost of an
// excitation against the activation's rate has a concave kink at u = a and switching costs less
// than any excitation the activation follows (a relaxed control): an infimum that smooth plans
// approach but do not reach.
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "flatsos/planner/collocation.hpp"
#include "flatsos/planner/effort.hpp"
#include "flatsos/planner/planned_excitation.hpp"
#include "open_loop/plan_along_path.hpp"
#include "path/path_rows.hpp"
#include "scenario_fixture.hpp"

namespace fpl = flatsos::planner;
namespace fpd = flatsos::planner::detail;

namespace {

constexpr double kSwitchingEnds_s = 0.15;  // the reference switches before, not after

// Quintic B-spline on the reference's mesh through its joint angles at every point.
fpl::JointPath reference_path(const fpl::CollocationResult& r) {
  std::vector<double> mesh;
  for (Eigen::Index i = 0; i < r.time_s.size(); i += 2) mesh.push_back(r.time_s[i]);
  const fpl::BSplineBasis basis(5, mesh);
  Eigen::MatrixXd rows(r.time_s.size(), basis.size());
  for (Eigen::Index i = 0; i < r.time_s.size(); ++i)
    rows.row(i) = basis.derivativeRow(r.time_s[i], 0);
  const Eigen::MatrixXd coefficients =
      rows.colPivHouseholderQr().solve(r.joint_angle_rad.transpose()).transpose();
  return fpl::JointPath::fromSpline(fpl::SplineTrajectory(basis, coefficients));
}

// The largest jump of any muscle's excitation at point i against the mean of its neighbours.
double switching_at(const fpl::CollocationResult& r, Eigen::Index i) {
  return (r.excitation.col(i) - 0.5 * (r.excitation.col(i - 1) + r.excitation.col(i + 1)))
      .cwiseAbs()
      .maxCoeff();
}

}  // namespace

TEST(RelaxedReference,
     AlongTheReferencesPathTheFlatnessPlanCostsTheSameOnceTheReferenceStopsSwitching) {
  flatsos::test::ArmPlanning arm;
  const fpl::MuscleState s0 = flatsos::test::open_loop_initial_state(*arm.model);
  fpl::OpenLoopOptions o;
  o.duration_s = 3.0;
  o.target_q_rad = flatsos::test::open_loop_options().target_q_rad;
  o.reserves_N = flatsos::test::open_loop_options().reserves_N;
  o.effort = fpl::effort_named("excitation_squared");
  auto ws = arm.flat.makeWorkspace();
  const fpl::OpenLoopPlan prescribed = fpl::plan_open_loop(arm.flat, ws, s0, o);
  ASSERT_EQ(prescribed.status, fpl::SolveStatus::Solved) << prescribed.message;
  fpl::CollocationOptions co;
  co.effort = o.effort;
  co.mesh_intervals = 200;
  co.mesh_interval_growth = 1.02;
  const fpl::CollocationResult reference =
      fpl::solve_collocation_free_path(arm.flat, ws, prescribed.path, s0, o.reserves_N, co);
  ASSERT_EQ(reference.status, fpl::SolveStatus::Solved) << reference.message;

  // The reference's path in the free path's spline (degree 8 through the flatness plan's
  // boundary conditions, 48 spans growing from t = 0), then the flatness plan along it.
  fpl::FreeJointPathOptions spline;
  spline.spans = 48;
  spline.span_growth = std::pow(1.2, 0.25);
  const fpd::FreePathSettings settings(spline, fpl::FreePathStudyOptions{});
  const fpl::FlatState y0 = arm.flat.forward(ws, s0);
  const fpd::PathParameterization P =
      fpd::parameterize(settings, o.duration_s, y0.q, o.target_q_rad);
  fpl::OpenLoopPlan plan;
  plan.path = P.path(fpd::fit_to(P, reference_path(reference)));
  double path_error_rad = 0.0;
  for (Eigen::Index i = 0; i < reference.time_s.size(); ++i)
    path_error_rad = std::max(path_error_rad, (plan.path.jet(reference.time_s[i], 1).col(0) -
                                               reference.joint_angle_rad.col(i))
                                                  .cwiseAbs()
                                                  .maxCoeff());
  EXPECT_LT(path_error_rad, flatsos::test::deg(0.05));
  fpl::FlatOutputBoundary bc;
  bc.initial = y0.Y;
  bc.terminal = Eigen::MatrixXd::Zero(arm.flat.numFlatOutputs(), 2);
  bc.terminal_first_order = 1;
  fpl::OpenLoopOptions along = fpl::resolve_basis(arm.flat, o);
  along.sos.effort = o.effort;
  fpd::plan_along_path(arm.flat, ws, bc, along, fpl::OpenLoopStudyOptions{}, plan);
  ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;

  // Each cost from the first mesh point at or after kSwitchingEnds_s: the reference's by
  // Simpson's rule, the plan's by the trapezoidal rule on 10 us steps of its excitations.
  const Eigen::VectorXd& t = reference.time_s;
  const Eigen::Index intervals = (t.size() - 1) / 2;
  Eigen::Index first = 0;
  while (t[2 * first] < kSwitchingEnds_s) ++first;
  double reference_tail = 0.0;
  for (Eigen::Index k = first; k < intervals; ++k) {
    const auto squares = [&](Eigen::Index i) { return reference.excitation.col(i).squaredNorm(); };
    reference_tail += (t[2 * k + 2] - t[2 * k]) / 6.0 *
                      (squares(2 * k) + 4.0 * squares(2 * k + 1) + squares(2 * k + 2));
  }
  const auto excitations = fpl::PlannedExcitation::create(arm.flat, plan.path, *plan.Y);
  const auto squares = [&](double time_s) {
    double sum = 0.0;
    for (int j = 0; j < arm.model->numMuscles(); ++j)
      sum += std::pow(excitations->excitation(j, time_s), 2);
    return sum;
  };
  const int steps = static_cast<int>(std::round((o.duration_s - t[2 * first]) / 1e-5));
  const double h = (o.duration_s - t[2 * first]) / steps;
  double plan_tail = 0.5 * (squares(t[2 * first]) + squares(o.duration_s));
  for (int i = 1; i < steps; ++i) plan_tail += squares(t[2 * first] + i * h);
  plan_tail *= h;
  std::printf(
      "along the reference's path: plan %.7f s (%+.2f %%), from %.3f s on plan %.7f s, reference "
      "%.7f s (%+.3f %%)\n",
      plan.sos.effort_value, 100.0 * (plan.sos.effort_value / reference.cost - 1.0), t[2 * first],
      plan_tail, reference_tail, 100.0 * (plan_tail / reference_tail - 1.0));
  EXPECT_NEAR(plan_tail, reference_tail, 2e-3 * reference_tail);  // measured 0.07 %
  EXPECT_GT(plan.sos.effort_value, reference.cost);               // the infimum: 3.7 % lower

  // Before, the reference switches: excitations jump by at least 0.4 against their neighbours'
  // mean at many points (0 and 1 in turn); after, nowhere by more than 0.05.
  int switching = 0;
  for (Eigen::Index i = 1; i < 2 * first; ++i)
    switching += switching_at(reference, i) > 0.4 ? 1 : 0;
  EXPECT_GE(switching, 20);
  double calm = 0.0;
  for (Eigen::Index i = 2 * first + 1; i + 1 < t.size(); ++i)
    calm = std::max(calm, switching_at(reference, i));
  EXPECT_LT(calm, 0.05);
}
