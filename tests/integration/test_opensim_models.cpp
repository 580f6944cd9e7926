// The two models made from OpenSim's example by opensim_to_model (models/seated_knee_r.json: the
// seated right knee, 13 muscles; models/sagittal_leg_r.json: hip, knee and ankle, 40 muscles), in
// the scenarios they ship with: the open-loop plan is executed by Simbody as planned; the SOS
// optimum is within 1 % above an independent dense-grid bound; the receding-horizon loop reaches
// its target, also on a plant 20 % weaker or stronger than the planner's model with the
// disturbance observer. Each test prints what it measured.
#include <gtest/gtest.h>

#include <iostream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "../planner/scenario_fixture.hpp"
#include "flatsos/planner/numerics/simplex_lp.hpp"
#include "flatsos/planner/receding_horizon_controller.hpp"
#include "flatsos/planner/rest_state.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "open_loop_replay.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
using flatsos::test::deg;

namespace {

struct ShippedModel {
  explicit ShippedModel(const std::string& name)
      : description(fp::load_model_file(std::string(FLATSOS_SOURCE_DIR) + "/models/" + name + ".json")),
        model(std::make_shared<const fp::MusculoskeletalModel>(description)),
        flat(model) {}
  fp::ModelDescription description;
  std::shared_ptr<const fp::MusculoskeletalModel> model;
  fpl::FlatOutputMap flat;

  const fp::ScenarioDescription& scenario(const std::string& name) const {
    const fp::ScenarioDescription* s = description.scenario(name);
    if (!s) throw std::logic_error("the model has no scenario '" + name + "'");
    return *s;
  }
  Eigen::VectorXd reserves(const fp::ScenarioDescription& s) const {
    return s.reserves_N.size() == 1 ? Eigen::VectorXd::Constant(model->numMuscles(), s.reserves_N[0]) : s.reserves_N;
  }
  // The open-loop scenario from the model's minimum-effort rest at its start.
  fpl::MuscleState rest(const fp::ScenarioDescription& s) const {
    SimTK::State state = model->defaultState();
    fpl::set_minimum_effort_rest_state(flat, state, s.q0_rad, reserves(s));
    return fpl::muscle_state_of(*model, state);
  }
  fpl::OpenLoopOptions openLoopOptions() const {
    const fp::ScenarioDescription& s = scenario("open_loop");
    fpl::OpenLoopOptions o = fpl::open_loop_options(fpl::Preset::Paper);
    o.duration_s = s.duration_s;
    o.target_q_rad = s.target_q_rad;
    o.reserves_N = reserves(s);
    return o;
  }
};

const char* const kModels[] = {"seated_knee_r", "sagittal_leg_r"};

// The effort's lower bound, independent of the SOS program (no torque model, no coupling
// polynomials, no exchange): the plan's own B-spline space for the flat outputs, the boundary
// conditions as equality rows, and F = C(q)^-1 [tau; Y] >= reserve and Y >= 0 only at `points`
// grid times, with C = [R(q); E] inverted here and the exact inverse-dynamics torques; the cost
// integral of w . F by the trapezoid rule on the same grid. A relaxation: its optimum is below
// the same quadrature of the plan's own F, which it returns beside it.
struct DenseGridBound {
  double bound_N_s = 0.0, plan_N_s = 0.0;
};

DenseGridBound dense_grid_bound(const fpl::FlatOutputMap& flat, const fpl::OpenLoopPlan& plan, const fpl::MuscleState& s0,
                                const Eigen::VectorXd& reserves, int points) {
  const fpl::SplineTrajectory& Y = *plan.sos.Y;
  const fpl::BSplineBasis& basis = Y.basis();
  const double T = basis.duration();
  const int n = flat.numJoints(), m = flat.numMuscles(), p = flat.numFlatOutputs(), size = basis.size(), nv = p * size;
  const Eigen::VectorXd& w = flat.effortWeights();
  const fpl::FlatState y0 = flat.forward(s0);
  std::vector<Eigen::RowVectorXd> rows;
  std::vector<double> lower;
  auto add = [&](const Eigen::RowVectorXd& r, double l) { rows.push_back(r), lower.push_back(l); };
  std::vector<Eigen::RowVectorXd> equalities;
  std::vector<double> equal_to;
  for (int l = 0; l < p; ++l) {
    for (int order = 0; order < 2; ++order) {
      equalities.push_back(Eigen::RowVectorXd::Zero(nv));
      equalities.back().segment(l * size, size) = basis.derivativeRow(0.0, order);
      equal_to.push_back(y0.Y(l, order));
    }
    for (int order = 1; order < 3; ++order) {
      equalities.push_back(Eigen::RowVectorXd::Zero(nv));
      equalities.back().segment(l * size, size) = basis.derivativeRow(T, order);
      equal_to.push_back(0.0);
    }
  }
  Eigen::VectorXd cost = Eigen::VectorXd::Zero(nv);
  double constant = 0.0;
  DenseGridBound out;
  for (int i = 0; i < points; ++i) {
    const double t = T * i / (points - 1), weight = (i == 0 || i == points - 1 ? 0.5 : 1.0) * T / (points - 1);
    const fpl::Jet q = plan.path.jet(t, 3);
    const Eigen::VectorXd tau = flat.torque(q.col(0), q.col(1), q.col(2));
    Eigen::MatrixXd C(m, m);
    C << flat.model().momentArmMatrix(q.col(0)), flat.E();
    const Eigen::MatrixXd Cinv = C.fullPivLu().inverse();
    const Eigen::RowVectorXd B = basis.derivativeRow(t, 0);
    for (int k = 0; k < m; ++k) {
      Eigen::RowVectorXd r(nv);
      for (int l = 0; l < p; ++l) r.segment(l * size, size) = Cinv(k, n + l) * B;
      add(r, reserves[k] - Cinv.row(k).head(n).dot(tau));
    }
    for (int l = 0; l < p; ++l) {
      Eigen::RowVectorXd r = Eigen::RowVectorXd::Zero(nv);
      r.segment(l * size, size) = B;
      add(r, 0.0);
    }
    const Eigen::RowVectorXd wY = w.transpose() * Cinv.rightCols(p);  // d(w . F)/dY
    for (int l = 0; l < p; ++l) cost.segment(l * size, size) += weight * wY[l] * B.transpose();
    const double w_tau = w.dot(Cinv.leftCols(n) * tau);
    constant += weight * w_tau;
    out.plan_N_s += weight * (w_tau + wY.dot(Y.jet(t, 1).col(0)));
  }
  fpl::LinearProgram lp;
  lp.cost = cost;
  const Eigen::Index total = static_cast<Eigen::Index>(rows.size() + equalities.size());
  lp.G.resize(total, nv);
  lp.row_lower.resize(total);
  lp.row_upper.resize(total);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    lp.G.row(static_cast<Eigen::Index>(r)) = rows[r];
    lp.row_lower[static_cast<Eigen::Index>(r)] = lower[r];
    lp.row_upper[static_cast<Eigen::Index>(r)] = 1e19;
  }
  for (std::size_t r = 0; r < equalities.size(); ++r) {
    const auto at = static_cast<Eigen::Index>(rows.size() + r);
    lp.G.row(at) = equalities[r];
    lp.row_lower[at] = lp.row_upper[at] = equal_to[r];
  }
  lp.x_lower = Eigen::VectorXd::Constant(nv, -1e6);
  lp.x_upper = Eigen::VectorXd::Constant(nv, 1e6);
  const fpl::LinearProgramResult r = fpl::solve_linear_program_simplex(lp);
  EXPECT_EQ(r.status, fpl::SolveStatus::Solved) << r.solver_status;
  out.bound_N_s = constant + r.objective;
  return out;
}

}  // namespace

TEST(OpenSimModels, OpenLoopPlansAreExecutedBySimbodyAsPlanned) {
  for (const char* name : kModels) {
    SCOPED_TRACE(name);
    const ShippedModel shipped(name);
    const fpl::OpenLoopOptions o = shipped.openLoopOptions();
    const fpl::MuscleState s0 = shipped.rest(shipped.scenario("open_loop"));
    const fpl::OpenLoopPlan plan = fpl::plan_open_loop(shipped.flat, s0, o);
    ASSERT_EQ(plan.status, fpl::SolveStatus::Solved) << plan.message;
    EXPECT_TRUE(plan.sos.certified);
    const flatsos::test::OpenLoopReplay replay = flatsos::test::replay_open_loop(shipped.flat, s0, plan, 1e-10, 0.005);
    ASSERT_TRUE(replay.sim.finite) << replay.sim.message;
    std::cout << name << ": cost " << plan.sos.cost_N_s << " N s, bounds imposed " << plan.sos.bounds_imposed
              << "; replayed within " << replay.max_q_error_rad / deg(1) << " deg, activation " << replay.max_activation_error
              << ", tendon " << replay.max_tendon_length_error_m << " m\n";
    EXPECT_LT(replay.max_q_error_rad, deg(1e-5));
    EXPECT_LT(replay.max_activation_error, 1e-6);
    EXPECT_GE(replay.min_tendon_force_N, o.reserves_N.minCoeff() - 1e-6);
    const Eigen::VectorXd q_end = shipped.model->jointAngles(replay.sim.final_state);
    EXPECT_LT((q_end - o.target_q_rad).cwiseAbs().maxCoeff(), deg(1e-5));
  }
}

TEST(OpenSimModels, TheSosOptimumIsWithinOnePercentAboveAnIndependentDenseGridBound) {
  // Of the program with the reserves only (the bound is an LP; the excitation bounds are not).
  // Its optimum asks some muscles for activations outside [floor, 1] (which is why the shipped
  // plans impose the bounds), so the plan as a whole is refused; the program itself is solved.
  for (const char* name : kModels) {
    SCOPED_TRACE(name);
    const ShippedModel shipped(name);
    fpl::OpenLoopOptions o = shipped.openLoopOptions();
    o.sos.bounds.enforce = false;
    const fpl::MuscleState s0 = shipped.rest(shipped.scenario("open_loop"));
    const fpl::OpenLoopPlan plan = fpl::plan_open_loop(shipped.flat, s0, o);
    ASSERT_EQ(plan.sos.status, fpl::SolveStatus::Solved) << plan.sos.message;
    ASSERT_TRUE(plan.sos.Y);
    ASSERT_FALSE(plan.sos.bounds_imposed);
    const DenseGridBound b = dense_grid_bound(shipped.flat, plan, s0, o.reserves_N, 201);
    std::cout << name << ": SOS optimum " << plan.sos.cost_N_s << " N s (its exact F on the grid: " << b.plan_N_s
              << "), dense-grid bound " << b.bound_N_s << " N s: " << 100.0 * (b.plan_N_s / b.bound_N_s - 1.0) << " % above\n";
    EXPECT_GE(b.plan_N_s, b.bound_N_s - 1e-7 * b.bound_N_s);
    EXPECT_LE(b.plan_N_s, 1.01 * b.bound_N_s);
    // The program's cost (modelled coupling) is the exact one to well within that.
    EXPECT_NEAR(plan.sos.cost_N_s, b.plan_N_s, 1e-3 * b.plan_N_s);
  }
}

TEST(OpenSimModels, TheRecedingHorizonLoopReachesItsTargetAlsoOnAWeakerOrStrongerPlant) {
  for (const char* name : kModels) {
    SCOPED_TRACE(name);
    const ShippedModel shipped(name);
    const fp::ScenarioDescription& s = shipped.scenario("receding_horizon");
    const Eigen::VectorXd reserves = shipped.reserves(s);
    struct Case {
      double strength, observer_gain_per_s;
    };
    for (const Case c : {Case{1.0, 0.0}, Case{0.8, 20.0}, Case{1.2, 20.0}}) {
      fp::ModelDescription plant_description = shipped.description;
      for (auto& muscle : plant_description.muscles) muscle.parameters.max_isometric_force_N *= c.strength;
      const auto plant = std::make_shared<const fp::MusculoskeletalModel>(plant_description);
      fpl::RecedingHorizonControllerOptions o;
      o.plan.target_q_rad = s.target_q_rad;
      o.plan.reserves_N = reserves;
      o.disturbance_observer_gain_per_s = c.observer_gain_per_s;
      fpl::RecedingHorizonController controller(shipped.flat, o, plant);
      SimTK::State start = plant->defaultState();
      fpl::set_minimum_effort_rest_state(fpl::FlatOutputMap(plant), start, s.q0_rad, reserves);
      fp::ClosedLoopOptions loop;
      loop.duration_s = s.duration_s + 1.5;
      loop.integrator = fp::IntegratorKind::MuscleRosenbrock;
      loop.accuracy = 1e-6;
      const fpl::RecedingHorizonRun run = fpl::run_receding_horizon(controller, start, loop, deg(0.5));
      ASSERT_TRUE(run.loop.finite);
      const double error_deg = (plant->jointAngles(run.loop.final_state) - s.target_q_rad).cwiseAbs().maxCoeff() / deg(1);
      std::cout << name << ", plant strength x" << c.strength << ", observer " << c.observer_gain_per_s << "/s: ends "
                << error_deg << " deg from the target (within 0.5 deg from " << run.settling_time_s << " s), "
                << controller.planFailures() << " failed plans, " << controller.clampedSamples() << " clamped samples\n";
      EXPECT_LT(error_deg, 0.5);
      EXPECT_GE(run.settling_time_s, 0.0);
      EXPECT_EQ(controller.planFailures(), 0);
    }
  }
}
