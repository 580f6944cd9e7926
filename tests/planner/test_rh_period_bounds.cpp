// Bounded receding-horizon steps: the first period's excitations in [0, 1] and activations in
// [floor, 1] by construction, at a local optimum of the bounded step (first-order conditions with
// finite-difference gradients of the sampled inverse map, independent of the bound rows'
// analytic gradients), the reserves kept; infeasible bounds named.
#include <gtest/gtest.h>

#include <Eigen/QR>

#include "flatsos/planner/receding_horizon_study.hpp"
#include "first_period_constraints.hpp"
#include "receding_horizon/period_bounds.hpp"
#include "scenario_fixture.hpp"

namespace fpl = flatsos::planner;
namespace fp = flatsos::plugin;
namespace fpd = flatsos::planner::detail;
using flatsos::test::deg;

namespace {

struct PaperFirstStep {
  flatsos::test::ArmPlanning arm;
  fp::ModelWorkspace ws = arm.flat.makeWorkspace();
  fpl::RecedingHorizonOptions options = [] {
    fpl::RecedingHorizonOptions o;
    o.target_q_rad = Eigen::Vector2d(deg(80), deg(80));
    o.reserves_N = Eigen::VectorXd::Constant(6, 1.0);
    return o;
  }();
  Eigen::Vector2d q{deg(20), deg(20)}, qd{0.0, 0.0};

  fpl::RecedingHorizonStep plan(bool bounds) {
    fpl::RecedingHorizonOptions o = options;
    o.excitation_bounds.enforce = bounds;
    return fpl::plan_receding_horizon_step(arm.flat, ws, q, qd, o);
  }
  // The first period's samples of a plan with flat outputs alpha: excitations and activations.
  bool sample(const fpl::RecedingHorizonStep& step, const Eigen::VectorXd& alpha, Eigen::MatrixXd& n, Eigen::MatrixXd& a) {
    const auto& b = options.excitation_bounds;
    fpl::PlanExcitationScratch scratch;
    return fpl::sample_plan_excitations(arm.flat, ws, step.path, alpha, step.torque_offset_N_m, 0.0,
                                        b.period_s / (b.samples - 1), b.samples, scratch, n, &a);
  }
};

// Every constraint of the bounded step as c(alpha) >= 0 (first_period_constraints.hpp).
Eigen::VectorXd constraints(PaperFirstStep& s, const fpl::RecedingHorizonStep& step, const Eigen::VectorXd& alpha) {
  return flatsos::test::first_period_constraints(s.arm.flat, s.ws, s.options.excitation_bounds, step, alpha);
}

// The seated knee (13 muscles, 1 N reserves) moving from 60 to 20 degrees, one period after
// another: most muscles' SLP optimum sits 100 N below their activation floor, so every step is
// bounded.
struct KneePeriods {
  std::shared_ptr<const fp::MusculoskeletalModel> model =
      fp::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) + "/models/seated_knee_r.json");
  fpl::FlatOutputMap flat{model};
  fp::ModelWorkspace ws = flat.makeWorkspace();
  fpl::RecedingHorizonOptions o = [] {
    fpl::RecedingHorizonOptions options;
    options.target_q_rad = Eigen::VectorXd::Constant(1, deg(20));
    options.reserves_N = Eigen::VectorXd::Constant(13, 1.0);
    return options;
  }();
  Eigen::VectorXd q = Eigen::VectorXd::Constant(1, deg(60)), qd = Eigen::VectorXd::Constant(1, -1.0);

  void nextPeriod() {
    q[0] -= 0.05;
    qd[0] = -1.1;
  }
};

}  // namespace

TEST(RecedingHorizonStepBounds, KeepTheFirstPeriodInsideAtAFirstOrderOptimum) {
  PaperFirstStep s;
  const auto free = s.plan(false);
  ASSERT_EQ(free.status, fpl::SolveStatus::Solved) << free.message;
  EXPECT_FALSE(free.bounds_imposed);
  Eigen::MatrixXd n, a;
  ASSERT_TRUE(s.sample(free, free.alpha(), n, a));
  // Precondition: the paper's step asks the anterior deltoid for more than 1 in the first period.
  ASSERT_GT(n.maxCoeff(), 1.01);

  const auto bounded = s.plan(true);
  ASSERT_EQ(bounded.status, fpl::SolveStatus::Solved) << bounded.message;
  EXPECT_TRUE(bounded.bounds_imposed);
  EXPECT_GT(bounded.bound_iterations, 0);
  EXPECT_EQ(bounded.bound_N, free.bound_N);
  EXPECT_NEAR(bounded.slp.cost_N, bounded.alpha().sum(), 1e-12);
  EXPECT_GT(bounded.slp.cost_N, free.slp.cost_N);  // the bounds cost effort
  const Eigen::VectorXd c = constraints(s, bounded, bounded.alpha());
  EXPECT_GE(c.head(c.size() - 10).minCoeff(), 0.0);           // a, n inside, exactly
  EXPECT_GE(c.segment(c.size() - 10, 6).minCoeff(), -1e-6);   // reserves (N)
  EXPECT_GE(bounded.alpha().minCoeff(), 0.0);
  // What the controller would apply: the step's own excitations.
  const Eigen::MatrixXd applied = bounded.excitations(s.arm.flat, s.ws, 0.0, 0.005, 11);
  EXPECT_GE(applied.minCoeff(), 0.0);
  EXPECT_LE(applied.maxCoeff(), 1.0);

  // First order: the cost gradient (all ones) is a nonnegative combination of the active
  // constraints' gradients, taken by central differences of the sampled inverse map.
  const Eigen::VectorXd alpha = bounded.alpha();
  const int p = static_cast<int>(alpha.size());
  std::vector<int> active;
  for (Eigen::Index k = 0; k < c.size(); ++k)
    if (c[k] < 1e-3) active.push_back(static_cast<int>(k));
  ASSERT_FALSE(active.empty());
  ASSERT_LE(static_cast<int>(active.size()), p) << "degenerate: more active constraints than flat outputs";
  Eigen::MatrixXd J(p, static_cast<Eigen::Index>(active.size()));
  const double h = 1e-4;
  for (int l = 0; l < p; ++l) {
    Eigen::VectorXd up = alpha, down = alpha;
    up[l] += h;
    down[l] -= h;
    const Eigen::VectorXd dc = (constraints(s, bounded, up) - constraints(s, bounded, down)) / (2 * h);
    for (std::size_t k = 0; k < active.size(); ++k) J(l, static_cast<Eigen::Index>(k)) = dc[active[k]];
  }
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(p);
  const Eigen::VectorXd mu = J.colPivHouseholderQr().solve(ones);
  EXPECT_LT((J * mu - ones).norm(), 1e-4 * std::sqrt(p)) << "not stationary: multipliers " << mu.transpose();
  EXPECT_GE(mu.minCoeff(), 0.0) << "a negative multiplier: the cost still falls along some active constraint";
}

TEST(RecedingHorizonStepBounds, TheNextPeriodStartsFromTheLastBoundedOptimum) {
  // A controller plans into the same step every period: its bounds' sequential LP starts from
  // the last bounded alpha when that violates less than the SLP's optimum. The seated knee (13
  // muscles, 1 N reserves): most muscles' SLP optimum sits 100 N below their activation floor.
  // Same optimum as a step planned afresh, in fewer LP steps; and the LP basis it keeps from
  // the last period saves simplex pivots over the same start without it.
  KneePeriods knee;
  auto& [model, flat, ws, o, q, qd] = knee;
  fpl::RecedingHorizonStep reused;
  fpl::plan_receding_horizon_step(flat, ws, q, qd, o, reused);
  ASSERT_EQ(reused.status, fpl::SolveStatus::Solved) << reused.message;
  ASSERT_TRUE(reused.bounds_imposed);
  ASSERT_EQ(reused.buffers.bounded_alpha, reused.alpha());
  ASSERT_FALSE(reused.buffers.bounds_basis.bound_row.empty());
  reused.buffers.bounds_active_set.clear();  // the sequential LP, not Newton's method on the last vertex (below)
  fpl::RecedingHorizonStep without_basis = reused;
  without_basis.buffers.bounds_basis = fpl::SequentialLpBasis{};
  knee.nextPeriod();
  fpl::plan_receding_horizon_step(flat, ws, q, qd, o, reused);
  fpl::plan_receding_horizon_step(flat, ws, q, qd, o, without_basis);
  ASSERT_EQ(without_basis.status, fpl::SolveStatus::Solved) << without_basis.message;
  EXPECT_NEAR(reused.slp.cost_N, without_basis.slp.cost_N, 1e-9 * without_basis.slp.cost_N);
  EXPECT_LT(reused.bound_lp_pivots, without_basis.bound_lp_pivots);
  std::cout << "[ measure  ] next period: " << reused.bound_iterations << " LP steps, " << reused.bound_lp_pivots
            << " pivots; without the last basis " << without_basis.bound_lp_pivots << "\n";
  const auto fresh = fpl::plan_receding_horizon_step(flat, ws, q, qd, o);
  ASSERT_EQ(reused.status, fpl::SolveStatus::Solved) << reused.message;
  ASSERT_EQ(fresh.status, fpl::SolveStatus::Solved) << fresh.message;
  ASSERT_TRUE(fresh.bounds_imposed && reused.bounds_imposed);
  EXPECT_NEAR(reused.slp.cost_N, fresh.slp.cost_N, 1e-6 * fresh.slp.cost_N);
  EXPECT_LT((reused.alpha() - fresh.alpha()).cwiseAbs().maxCoeff(), 1e-4 * (1 + fresh.alpha().cwiseAbs().maxCoeff()));
  EXPECT_LT(reused.bound_iterations, fresh.bound_iterations);
}

TEST(RecedingHorizonStepBounds, TheNextPeriodHoldsTheLastActiveRowsByNewtonsMethodWhereTheyStillBind) {
  // The seated knee one period later, as above: the last period's active bound rows (its
  // vertex) still make the optimum's. Newton's method on them ends there without an LP step, at
  // the sequential LP's plan.
  KneePeriods knee;
  auto& [model, flat, ws, o, q, qd] = knee;
  fpl::RecedingHorizonStep newton;
  fpl::plan_receding_horizon_step(flat, ws, q, qd, o, newton);
  ASSERT_EQ(newton.status, fpl::SolveStatus::Solved) << newton.message;
  ASSERT_EQ(newton.buffers.bounds_active_set.size(), static_cast<std::size_t>(flat.numFlatOutputs()));
  fpl::RecedingHorizonStep by_lp = newton;
  by_lp.buffers.bounds_active_set.clear();
  knee.nextPeriod();
  fpl::plan_receding_horizon_step(flat, ws, q, qd, o, newton);
  fpl::plan_receding_horizon_step(flat, ws, q, qd, o, by_lp);
  ASSERT_EQ(newton.status, fpl::SolveStatus::Solved) << newton.message;
  ASSERT_EQ(by_lp.status, fpl::SolveStatus::Solved) << by_lp.message;
  EXPECT_TRUE(newton.first_period_sampled);
  EXPECT_GE(newton.bound_newton_steps, 1);
  EXPECT_EQ(newton.bound_iterations, 0);
  EXPECT_EQ(newton.bound_lp_pivots, 0);
  EXPECT_GE(by_lp.bound_iterations, 1);
  // Here the sequential LP reaches the vertex itself (3e-12 N apart when written).
  EXPECT_NEAR(newton.slp.cost_N, by_lp.slp.cost_N, 1e-9 * by_lp.slp.cost_N);
  EXPECT_LT((newton.alpha() - by_lp.alpha()).cwiseAbs().maxCoeff(), 1e-8 * (1 + by_lp.alpha().cwiseAbs().maxCoeff()));
  // Every sample of the applied plan inside its bounds (what first_period_sampled vouches for).
  EXPECT_GE(newton.buffers.activations.minCoeff(), model->muscle(0).getParameters().activation_floor - 1e-12);
  EXPECT_GE(newton.buffers.excitations.minCoeff(), 0.0);
  EXPECT_LE(newton.buffers.excitations.maxCoeff(), 1.0);
  // Those are the bound points' inverse at the final alpha (kept from Newton's last evaluation).
  const Eigen::MatrixXd kept_n = newton.buffers.excitations, kept_a = newton.buffers.activations;
  ASSERT_TRUE(fpd::sampled_at_points(flat, fpd::period_points(flat, o.excitation_bounds, newton), newton));
  EXPECT_EQ(kept_n, newton.buffers.excitations);
  EXPECT_EQ(kept_a, newton.buffers.activations);
  std::cout << "[ measure  ] next period: " << newton.bound_newton_steps << " Newton steps; by the sequential LP "
            << by_lp.bound_iterations << " LP steps; cost " << newton.slp.cost_N - by_lp.slp.cost_N << " N apart, alpha "
            << (newton.alpha() - by_lp.alpha()).cwiseAbs().maxCoeff() << " N\n";
}

TEST(RecedingHorizonStepBounds, AStepThatNeedsNoBoundsIsTheSlpOptimum) {
  PaperFirstStep s;
  s.q = Eigen::Vector2d(deg(78), deg(79));  // near the target: gentle torques
  s.qd = Eigen::Vector2d(0.05, 0.02);
  const auto free = s.plan(false), bounded = s.plan(true);
  ASSERT_EQ(bounded.status, fpl::SolveStatus::Solved) << bounded.message;
  EXPECT_FALSE(bounded.bounds_imposed);
  EXPECT_EQ(bounded.bound_iterations, 0);
  EXPECT_EQ(bounded.alpha(), free.alpha());
}

TEST(RecedingHorizonStepBounds, InfeasibleBoundsAreReportedWithTheMuscleAndTime) {
  PaperFirstStep s;
  s.options.horizon_s = 0.3;  // 60 degrees in 0.3 s: no constant flat outputs can deliver it
  const auto bounded = s.plan(true);
  EXPECT_EQ(bounded.status, fpl::SolveStatus::Infeasible) << bounded.message;
  EXPECT_TRUE(bounded.bounds_imposed);
  EXPECT_NE(bounded.message.find("muscle '"), std::string::npos) << bounded.message;
  EXPECT_NE(bounded.message.find(" s: activation "), std::string::npos) << bounded.message;
}

TEST(RecedingHorizonStepBounds, ABoundsLpStuckAtALocalStationaryPointIsRestarted) {
  // The seated knee from rest to near its flexion limit: from the SLP's optimum (most flat outputs
  // at their reserve) the bounds' sequential LP settled 0.005 below vastus lateralis' activation
  // floor, in co-contraction, at each of these starts (an infeasible verdict, 1 step in 12000 of a
  // 10-minute run); feasible flat outputs exist there. Each step must now come out inside.
  const auto model = fp::MusculoskeletalModel::fromFile(std::string(FLATSOS_SOURCE_DIR) + "/models/seated_knee_r.json");
  const fpl::FlatOutputMap flat(model);
  fp::ModelWorkspace ws = flat.makeWorkspace();
  fpl::RecedingHorizonOptions o;
  o.target_q_rad = Eigen::VectorXd::Constant(1, deg(100.72));
  o.reserves_N = Eigen::VectorXd::Constant(13, 1.0);
  const auto& b = o.excitation_bounds;
  for (double start_deg : {94.1, 94.3, 94.5, 94.8}) {
    SCOPED_TRACE(start_deg);
    const auto step = fpl::plan_receding_horizon_step(flat, ws, Eigen::VectorXd::Constant(1, deg(start_deg)),
                                                      Eigen::VectorXd::Zero(1), o);
    ASSERT_EQ(step.status, fpl::SolveStatus::Solved) << step.message;
    ASSERT_TRUE(step.bounds_imposed);
    fpl::PlanExcitationScratch scratch;
    Eigen::MatrixXd n, a;
    ASSERT_TRUE(fpl::sample_plan_excitations(flat, ws, step.path, step.alpha(), step.torque_offset_N_m, 0.0,
                                             b.period_s / (b.samples - 1), b.samples, scratch, n, &a));
    for (int j = 0; j < flat.numMuscles(); ++j)
      EXPECT_GE(a.col(j).minCoeff(), model->muscle(j).getParameters().activation_floor) << "muscle " << j;
    EXPECT_LE(a.maxCoeff(), 1.0);
    EXPECT_GE(n.minCoeff(), 0.0);
    EXPECT_LE(n.maxCoeff(), 1.0);
    EXPECT_GE((step.reserve_rows * step.alpha() - step.bound_N).minCoeff(), -1e-6);  // reserves, N
    EXPECT_GE(step.alpha().minCoeff(), 0.0);
  }
}

TEST(RecedingHorizonStepBounds, BadBoundOptionsAreNamed) {
  PaperFirstStep s;
  auto rejects = [&](auto spoil, const std::string& field) {
    fpl::RecedingHorizonOptions o = s.options;
    spoil(o.excitation_bounds);
    try {
      fpl::plan_receding_horizon_step(s.arm.flat, s.ws, s.q, s.qd, o);
      ADD_FAILURE() << "accepted bad " << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  rejects([](auto& b) { b.period_s = 0.0; }, "excitation_bounds.period_s");
  rejects([](auto& b) { b.period_s = 0.6; }, "excitation_bounds.period_s");  // beyond the 0.5 s horizon
  rejects([](auto& b) { b.samples = 1; }, "excitation_bounds.samples");
  fpl::RecedingHorizonStudyOptions study;
  study.bound_max_iterations = 0;
  fpl::RecedingHorizonStep step;
  EXPECT_THROW(fpl::plan_receding_horizon_step(s.arm.flat, s.ws, s.q, s.qd, s.options, study, step), std::invalid_argument);
  fpl::RecedingHorizonOptions off = s.options;  // off, they are not checked
  off.excitation_bounds.enforce = false;
  off.excitation_bounds.samples = 1;
  EXPECT_EQ(fpl::plan_receding_horizon_step(s.arm.flat, s.ws, s.q, s.qd, off).status, fpl::SolveStatus::Solved);
}

TEST(RecedingHorizonStepBounds, AFirstPeriodOutsideTheDomainIsAFailedStepNotASolvedOne) {
  PaperFirstStep s;
  s.options.horizon_s = 0.1;  // 60 degrees in 0.1 s: fibres faster than they can shorten
  const auto free = s.plan(false);
  Eigen::MatrixXd n, a;
  ASSERT_EQ(free.status, fpl::SolveStatus::Solved);  // the SLP alone does not look at the excitations
  ASSERT_FALSE(s.sample(free, free.alpha(), n, a));
  const auto bounded = s.plan(true);
  EXPECT_EQ(bounded.status, fpl::SolveStatus::Failed);
  EXPECT_NE(bounded.message.find("leaves the model's valid domain on the first period: muscle '"), std::string::npos)
      << bounded.message;
}

TEST(RecedingHorizonStepBounds, TheBoundedStepsExcitationsAreThePlansOwnSamples) {
  // A bounded step hands the controller the excitations of its bound points (their torque jets
  // and force-jet maps are the samples'): the plan sampled again gives the same numbers.
  KneePeriods knee;
  fpl::RecedingHorizonStep step;
  fpl::plan_receding_horizon_step(knee.flat, knee.ws, knee.q, knee.qd, knee.o, step);
  ASSERT_EQ(step.status, fpl::SolveStatus::Solved) << step.message;
  ASSERT_TRUE(step.bounds_imposed);
  ASSERT_TRUE(step.first_period_sampled);
  const std::vector<fpd::BoundPoint> points = fpd::period_points(knee.flat, knee.o.excitation_bounds, step);
  step.buffers.excitations.setZero();
  ASSERT_TRUE(fpd::sampled_at_points(knee.flat, points, step));
  const Eigen::MatrixXd from_points = step.buffers.excitations, activations_from_points = step.buffers.activations;
  ASSERT_TRUE(fpd::sample_period(knee.flat, knee.ws, knee.o.excitation_bounds, step));
  ASSERT_EQ(from_points.rows(), step.buffers.excitations.rows());
  EXPECT_LT((from_points - step.buffers.excitations).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((activations_from_points - step.buffers.activations).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT(from_points.maxCoeff(), 0.01) << "nothing excited: nothing compared";
}
