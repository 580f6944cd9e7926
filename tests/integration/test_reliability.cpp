// Reliability: bad input of every kind gets a clear error naming the problem (one table), the RH
// loop survives failed plans on the previous plan's tail and recovers, and the forward
// simulation stays finite and bounded under extreme excitations.
#include <gtest/gtest.h>

#include <tuple>

#include <cmath>
#include <iomanip>
#include <fstream>
#include <functional>
#include <limits>

#include "../planner/scenario_fixture.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/muscles/hill_laws.hpp"
#include "rh_scenario.hpp"
#include "flatsos/plugin/io/excitation_file.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"

namespace fp = flatsos::plugin;
namespace fpl = flatsos::planner;
namespace fm = flatsos::muscles;
using flatsos::test::deg;

namespace {
const double kNaN = std::numeric_limits<double>::quiet_NaN();

struct BadInput {
  const char* what;
  std::function<void()> call;
  std::string message_contains;
};

std::string arm_text() {
  std::ifstream in(flatsos::test::arm_model_path());
  return std::string(std::istreambuf_iterator<char>(in), {});
}
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::logic_error("test setup: '" + from + "' not in the arm file");
  return text.replace(at, from.size(), to);
}

class Square : public fp::ExcitationSignal {
 public:
  Square(double hz, double phase) : hz_(hz), phase_(phase) {}
  double value(double t) const override { return std::fmod(t * hz_ + phase_, 1.0) < 0.5 ? 1.0 : 0.0; }

 private:
  double hz_, phase_;
};
}  // namespace

TEST(Reliability, EveryKindOfBadInputIsRejectedWithTheProblemNamed) {
  flatsos::test::ArmPlanning arm;
  const auto& model = *arm.model;
  const fpl::MuscleState s0 = flatsos::test::open_loop_initial_state(model);
  const fpl::OpenLoopOptions ol = flatsos::test::open_loop_options();
  fpl::RecedingHorizonOptions rh;
  rh.target_q_rad = Eigen::Vector2d(deg(80), deg(80));
  rh.reserves_N = Eigen::VectorXd::Constant(6, 1.0);
  const Eigen::Vector2d q(deg(20), deg(20)), zero2 = Eigen::Vector2d::Zero();
  const std::string text = arm_text();
  auto controller_with = [&](std::function<void(fpl::RecedingHorizonControllerOptions&)> spoil) {
    return [=, &arm] {
      fpl::RecedingHorizonControllerOptions o;
      o.plan = rh;
      spoil(o);
      fpl::RecedingHorizonController c(arm.flat, o);
    };
  };
  auto plan_with = [&](std::function<void(fpl::OpenLoopOptions&, fpl::MuscleState&)> spoil) {
    return [=, &arm] {
      auto o = ol;
      auto s = s0;
      spoil(o, s);
      fpl::plan_open_loop(arm.flat, s, o);
    };
  };
  auto rh_with = [&](std::function<void(fpl::RecedingHorizonOptions&)> spoil) {
    return [=, &arm] {
      auto o = rh;
      spoil(o);
      fpl::plan_receding_horizon_step(arm.flat, q, zero2, o);
    };
  };
  auto model_text = [](std::string t) { return [t] { fp::MusculoskeletalModel m(fp::parse_model_json(t, "bad.json")); }; };
  auto muscle_with = [&](std::function<void(fm::MuscleParameters&)> spoil) {
    return [=, &model] {
      auto p = model.muscle(0).getParameters();
      spoil(p);
      fm::validate(p);
    };
  };

  const std::vector<BadInput> cases = {
      // malformed or inconsistent model files
      {"truncated JSON", model_text(text.substr(0, text.size() / 2)), "not valid JSON"},
      {"negative mass", model_text(replaced(text, "\"mass_kg\": 2.24", "\"mass_kg\": -2.24")), "bodies[0].mass_kg"},
      {"unknown joint in a moment arm", model_text(replaced(text, "{\"shoulder\": 0.05}", "{\"shouldr\": 0.05}")), "unknown joint 'shouldr'"},
      {"pin axis zero", model_text(replaced(text, "\"location_in_parent_m\": [0.33, 0.0, 0.0]}", "\"location_in_parent_m\": [0.33, 0.0, 0.0], \"axis\": [0, 0, 0]}")), "axis"},
      {"E row count", model_text(replaced(text, ",\n    {\"name\": \"triceps_short_force\", \"weights\": {\"triceps_short\": 1.0}}", "")), "m - N = 4 rows"},
      {"E unknown muscle", model_text(replaced(text, "{\"triceps_short\": 1.0}", "{\"triceps\": 1.0}")), "unknown muscle 'triceps'"},
      {"unknown key", model_text(replaced(text, "\"name\": \"arm_richter_warner\",", "\"name\": \"arm_richter_warner\", \"gravity\": 9.81,")), "gravity: unknown key"},
      {"missing file", [] { fp::load_model_file("/no/such/model.json"); }, "cannot be opened"},
      // non-physical muscle parameters
      {"Fmax zero", muscle_with([](auto& p) { p.max_isometric_force_N = 0; }), "max_isometric_force_N"},
      {"Lopt NaN", muscle_with([](auto& p) { p.optimal_fiber_length_m = kNaN; }), "optimal_fiber_length_m"},
      {"gmax below 1", muscle_with([](auto& p) { p.max_eccentric_force_ratio = 0.8; }), "max_eccentric_force_ratio"},
      {"deactivation faster than activation", muscle_with([](auto& p) { p.deactivation_time_constant_s = 0.005; }), "activation_time_constant_s"},
      // boundary states outside the valid domain
      {"activation above 1", [&] { SimTK::State s = model.defaultState(); model.muscle(1).setActivation(s, 1.2); }, "outside [0, 1]"},
      {"negative tendon length", [&] { SimTK::State s = model.defaultState(); model.muscle(1).setTendonLength(s, -0.01); }, "tendon length"},
      {"initial activation 0", plan_with([](auto&, auto& s) { s.activation[3] = 0.0; }), "activation of 'triceps_long' is 0"},
      {"initial slack tendon", plan_with([](auto&, auto& s) { s.tendon_length_m[0] = 0.05; }), "tendon of 'anterior_deltoid' is slack"},
      {"initial NaN angle", plan_with([](auto&, auto& s) { s.q_rad[1] = kNaN; }), "q must have 2 finite values"},
      {"equilibrium without room", [&] { fp::static_equilibrium_tendon_length(model.muscle(5).getParameters(), 0.01, 0.5); }, "does not exceed the tendon slack length"},
      {"equilibrium activation NaN", [&] { fp::static_equilibrium_tendon_length(model.muscle(5).getParameters(), 0.15, kNaN); }, "activation"},
      // impossible targets, horizons, reserves
      {"target NaN", plan_with([](auto& o, auto&) { o.target_q_rad[0] = kNaN; }), "target joint angles: values must be finite"},
      {"target wrong size", plan_with([](auto& o, auto&) { o.target_q_rad = Eigen::Vector3d::Zero(); }), "target joint angles: expected 2"},
      {"duration zero", plan_with([](auto& o, auto&) { o.duration_s = 0.0; }), "duration T must be > 0"},
      {"duration infinite", plan_with([](auto& o, auto&) { o.duration_s = std::numeric_limits<double>::infinity(); }), "duration T must be > 0"},
      {"reserve negative", plan_with([](auto& o, auto&) { o.reserves_N[2] = -1.0; }), "reserves must be >= 0"},
      {"reserve NaN", plan_with([](auto& o, auto&) { o.reserves_N[2] = kNaN; }), "reserves: values must be finite"},
      {"pieces negative", plan_with([](auto& o, auto&) { o.torque.pieces = -1; }), "pieces K must be >= 1"},
      {"flat-output degree too low", plan_with([](auto& o, auto&) { o.sos.flat_output_degree = 2; }), "too low for 4 boundary equalities"},
      {"RH horizon negative", rh_with([](auto& o) { o.horizon_s = -0.5; }), "horizon must be > 0"},
      {"RH grid of one point", rh_with([](auto& o) { o.grid_points = 1; }), "at least 2 grid points"},
      {"RH reserves wrong size", rh_with([](auto& o) { o.reserves_N = Eigen::VectorXd::Ones(4); }), "reserves: expected 6"},
      {"RH state NaN", [&] { fpl::plan_receding_horizon_step(arm.flat, Eigen::Vector2d(kNaN, 0.0), zero2, rh); }, "joint angles: values must be finite"},
      {"RH period above horizon", [&] { fpl::RecedingHorizonControllerOptions o; o.plan = rh; o.control_period_s = 1.0; fpl::RecedingHorizonController c(arm.flat, o); }, "must not exceed the horizon"},
      // the controller checks its options when it is made (a bad option used to fail every step silently)
      {"RH controller reserves wrong size", controller_with([](auto& o) { o.plan.reserves_N = Eigen::VectorXd::Ones(4); }), "reserves: expected 6"},
      {"RH controller reserve negative", controller_with([](auto& o) { o.plan.reserves_N[1] = -2.0; }), "reserves must be >= 0"},
      {"RH controller target wrong size", controller_with([](auto& o) { o.plan.target_q_rad = Eigen::Vector3d::Zero(); }), "target joint angles: expected 2"},
      {"RH controller target NaN", controller_with([](auto& o) { o.plan.target_q_rad[1] = kNaN; }), "target joint angles: values must be finite"},
      {"RH controller horizon zero", controller_with([](auto& o) { o.plan.horizon_s = 0.0; }), "horizon must be > 0"},
      {"RH controller grid of one point", controller_with([](auto& o) { o.plan.grid_points = 1; }), "at least 2 grid points"},
      {"RH controller torque offset wrong size", controller_with([](auto& o) { o.plan.torque_offset_N_m = Eigen::VectorXd::Ones(3); }), "torque offset: expected 2"},
      {"RH controller one sample", controller_with([](auto& o) { o.excitation_samples_per_period = 1; }), "at least 2 excitation samples"},
      {"RH controller period NaN", controller_with([](auto& o) { o.control_period_s = kNaN; }), "control period must be > 0"},
      {"RH controller no planner", controller_with([](auto& o) { o.planner = nullptr; }), "no planner function"},
      {"RH controller plant of another size", [&] {
         fp::ModelDescription d = fp::load_model_file(flatsos::test::arm_model_path());
         d.muscles.pop_back();
         d.flat_outputs.clear();
         d.scenarios.clear();  // sized for six muscles
         fpl::RecedingHorizonControllerOptions o; o.plan = rh;
         fpl::RecedingHorizonController c(arm.flat, o, std::make_shared<const fp::MusculoskeletalModel>(d)); }, "other joints or muscles"},
      {"flat-output map without a model", [&] { fpl::FlatOutputMap f(nullptr); }, "no model"},
      // NaN and nonsense elsewhere
      {"RH observer gain NaN", [&] { fpl::RecedingHorizonControllerOptions o; o.plan = rh; o.disturbance_observer_gain_per_s = kNaN; fpl::RecedingHorizonController c(arm.flat, o); }, "observer gain must be a finite number >= 0"},
      {"unknown integrator", [&] { fp::integrator_from_name("rk4"); }, "unknown integrator 'rk4'"},
      {"simulation NaN state, Rosenbrock", [&] { SimTK::State s = model.defaultState(); s.updU()[1] = kNaN; fp::SimulationOptions o; o.integrator = fp::IntegratorKind::MuscleRosenbrock; fp::simulate(model, s, o); }, "initial state has a non-finite value"},
      {"excitation NaN", [&] { SimTK::State s = model.defaultState(); model.muscle(0).setExcitation(s, kNaN); }, "excitation is NaN"},
      {"simulation accuracy", [&] { fp::SimulationOptions o; o.accuracy = 0.0; fp::simulate(model, model.defaultState(), o); }, "accuracy"},
      {"simulation step limit", [&] { fp::SimulationOptions o; o.max_steps = -1; fp::simulate(model, model.defaultState(), o); }, "max_steps must be >= 0"},
      {"simulation NaN state", [&] { SimTK::State s = model.defaultState(); s.updQ()[0] = kNaN; fp::simulate(model, s, {}); }, "initial state has a non-finite value"},
      {"SLP NaN bound", [&] { fpl::solve_slp(arm.flat.CY(), Eigen::VectorXd::Constant(6, kNaN)); }, "NaN"},
      {"tendon force not positive", [&] { fm::tendon_length_from_force(model.muscle(2).getParameters(), -3.0); }, "biceps"},
      {"force-velocity beyond gmax", [&] { fm::force_velocity_inverse(model.muscle(2).getParameters(), 1.7); }, "(-Ah, gmax)"},
  };
  ASSERT_GE(cases.size(), 30u);
  for (const auto& c : cases) {
    try {
      c.call();
      ADD_FAILURE() << "accepted: " << c.what;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(c.message_contains), std::string::npos)
          << c.what << ": '" << c.message_contains << "' not in: " << e.what();
    }
  }
}

TEST(Reliability, FlatOutputsFixedCompletelyByTheEqualitiesStillGiveAnAnswer) {
  // Degree 3 with 4 boundary equalities leaves no free coefficient: nothing to optimize, but the
  // constraints must still be checked (this once read an empty vector's maximum and crashed).
  flatsos::test::ArmPlanning arm;
  auto o = flatsos::test::open_loop_options();
  o.sos.flat_output_degree = 3;
  const auto plan = fpl::plan_open_loop(arm.flat, flatsos::test::open_loop_initial_state(*arm.model), o);
  EXPECT_NE(plan.status, fpl::SolveStatus::Failed) << plan.message;
  if (plan.status == fpl::SolveStatus::Solved) EXPECT_GE(plan.check.min_reserve_margin_N, 0.0);
  else EXPECT_FALSE(plan.message.empty());
}

TEST(Reliability, ImpossibleMotionIsReportedNotPassedOff) {
  flatsos::test::ArmPlanning arm;
  auto o = flatsos::test::open_loop_options();
  o.duration_s = 0.6;  // straight up in 0.6 s needs more than the muscles can give
  const auto plan = fpl::plan_open_loop(arm.flat, flatsos::test::open_loop_initial_state(*arm.model), o);
  EXPECT_EQ(plan.status, fpl::SolveStatus::Infeasible);
  EXPECT_NE(plan.message.find("leaves the model's valid domain"), std::string::npos) << plan.message;
  EXPECT_GT(plan.check.points_outside_domain, 0);
  // The limiting muscle and quantity come first, from when, before the first grid point's verdict.
  ASSERT_FALSE(plan.check.limiting_violation.empty());
  const auto limiting_at = plan.message.find(plan.check.limiting_violation);
  EXPECT_LT(limiting_at, plan.message.find(plan.check.first_violation)) << plan.message;
  EXPECT_NE(plan.check.limiting_violation.find("(worst), from t = "), std::string::npos) << plan.check.limiting_violation;
  EXPECT_EQ(plan.check.limiting_violation.find("excitation"), std::string::npos)  // not an excitation when a more
      << plan.check.limiting_violation;                                           // fundamental quantity fails
  RecordProperty("message", plan.message);
}

TEST(Reliability, DomainViolationsRankByKindThenExcess) {
  using V = fpl::DomainViolation;
  EXPECT_DOUBLE_EQ((V{V::Kind::ActivationOutsideUnitInterval, 1.7, 1.0}).excess(), 0.7);
  EXPECT_DOUBLE_EQ((V{V::Kind::ActivationOutsideUnitInterval, -0.2, 1.0}).excess(), 0.2);
  EXPECT_DOUBLE_EQ((V{V::Kind::ExcitationOutsideUnitInterval, -0.0009, 1.0}).excess(), 0.0009);
  EXPECT_DOUBLE_EQ((V{V::Kind::SlackTendon, -3.0, 0.0}).excess(), 3.0);
  EXPECT_EQ((V{V::Kind::ActivationOutsideUnitInterval, std::numeric_limits<double>::infinity(), 1.0}).excess(),
            std::numeric_limits<double>::infinity());
  EXPECT_LT(V::Kind::ActivationOutsideUnitInterval, V::Kind::ExcitationOutsideUnitInterval);  // a before n
  EXPECT_EQ((V{}).describe(), "");
  EXPECT_EQ((V{V::Kind::ActivationOutsideUnitInterval, 1.7, 1.0}).describe(), "activation 1.7 outside (0, 1]");
}

TEST(Reliability, RecedingHorizonRunsOnThePreviousPlanWhenStepsFailAndRecovers) {
  flatsos::test::RecedingHorizonScenario rh;
  int calls = 0;
  rh.options.planner = [&](const fpl::FlatOutputMap& f, fp::ModelWorkspace& ws, const Eigen::VectorXd& q,
                           const Eigen::VectorXd& qd, const fpl::RecedingHorizonOptions& ro, fpl::RecedingHorizonStep& out) {
    const int k = calls++;
    if (k >= 5 && k < 9) {  // steps 5..8: the solver "fails" (and once throws)
      if (k == 7) throw std::runtime_error("injected solver crash");
      out.status = fpl::SolveStatus::Failed;
      out.message = "injected failure";
      return;
    }
    fpl::plan_receding_horizon_step(f, ws, q, qd, ro, out);
  };
  const auto outcome = rh.run(rh.loop(2.0, fp::IntegratorKind::CPodesBdf));
  const auto& run = outcome.run;
  const auto& controller = *outcome.controller;
  ASSERT_TRUE(run.loop.finite);
  EXPECT_EQ(controller.planFailures(), 4);
  const auto& h = controller.history();
  for (int k = 5; k < 9; ++k) {
    EXPECT_EQ(h[k].status, fpl::SolveStatus::Failed);
    EXPECT_TRUE(h[k].used_previous_plan) << k;
    EXPECT_DOUBLE_EQ(h[k].plan.start_time_s, h[4].plan.start_time_s);  // the tail of step 4's plan
    EXPECT_FALSE(h[k].message.empty());
  }
  EXPECT_NE(h[7].message.find("injected solver crash"), std::string::npos);
  EXPECT_EQ(h[9].status, fpl::SolveStatus::Solved);  // recovers
  ASSERT_GE(run.settling_time_s, 0.0);
  EXPECT_LT(outcome.final_error_deg, 1.0);
  // Settled, but the task failed: the run says so, with the first failure's time and message.
  EXPECT_FALSE(run.success());
  ASSERT_EQ(run.failures.size(), 1u);
  EXPECT_EQ(run.failures[0].rfind("4 of " + std::to_string(controller.steps()) + " plans failed", 0), 0u) << run.failures[0];
  EXPECT_NE(run.failures[0].find("the first at t = 0.25 s: injected failure"), std::string::npos) << run.failures[0];
}

class ExtremeExcitations : public ::testing::TestWithParam<std::tuple<int, fp::IntegratorKind>> {};

// 0: all excitations 0 for 5 s; 1: all 1 for 5 s; 2: bang-bang at 100 Hz for 5 s; with CPodes
// BDF and with the muscle Rosenbrock method.
TEST_P(ExtremeExcitations, ForwardSimulationStaysFiniteAndPhysicallyBounded) {
  const int kind_of_input = std::get<0>(GetParam());
  const auto arm = flatsos::test::load_arm();
  SimTK::State s = arm->defaultState();
  arm->setJointAngles(s, Eigen::Vector2d(0.0, deg(10)));
  fp::equilibrate_tendons(*arm, s, flatsos::test::paper_a0());
  for (int j = 0; j < 6; ++j) {
    if (kind_of_input == 2) arm->muscle(j).setExcitationSignal(s, std::make_shared<Square>(100.0, 0.5 * (j % 2)));
    else arm->muscle(j).setExcitation(s, kind_of_input == 1 ? 1.0 : 0.0);
  }
  fp::SimulationOptions o;
  o.duration_s = 5.0;
  o.accuracy = 1e-8;  // BDF needs it tight near the activation floor (see test_hill_muscle)
  o.report_interval_s = 0.01;
  o.integrator = std::get<1>(GetParam());
  const auto r = fp::simulate(*arm, s, o);
  ASSERT_TRUE(r.finite) << r.message;
  ASSERT_EQ(r.states.rows.size(), 501u);
  for (const auto& row : r.states.rows)
    for (double v : row) ASSERT_TRUE(std::isfinite(v));
  for (int j = 0; j < 6; ++j) {
    const auto& p = arm->muscle(j).getParameters();
    for (double a : r.states.column("/forceset/" + p.name + "/activation")) {
      EXPECT_GE(a, 0.0);
      EXPECT_LE(a - 1.0, 1e-12) << std::setprecision(17) << a;  // a -> 1 from below; round-off only
    }
    // Tendon force never exceeds what the fiber can hold eccentrically (gmax Fmax) by much:
    // the tendon stretches only as far as the fiber lets it.
    for (double f : r.states.column("/forceset/" + p.name + "/tendon_force")) EXPECT_LE(f, 1.6 * p.max_isometric_force_N);
    for (double ls : r.states.column("/forceset/" + p.name + "/tendon_length")) EXPECT_GT(ls, 0.5 * p.tendon_slack_length_m);
  }
  for (const char* joint : {"shoulder", "elbow"})
    for (double qd : r.states.column(std::string("/jointset/") + joint + "/" + joint + "/speed")) EXPECT_LT(std::abs(qd), 100.0);
}

INSTANTIATE_TEST_SUITE_P(ZeroOneBangBang, ExtremeExcitations,
                         ::testing::Combine(::testing::Values(0, 1, 2),
                                            ::testing::Values(fp::IntegratorKind::CPodesBdf, fp::IntegratorKind::MuscleRosenbrock)));
