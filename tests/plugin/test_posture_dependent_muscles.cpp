// An independent check of muscles whose paths depend on posture, with pennation and passive
// fibre force: a 1-joint elbow model (a flexor whose moment arm doubles between 0 and 90 degrees,
// through a polynomial path with a held coordinate; an extensor with a constant moment arm), loaded
// from a model file, simulated by Simbody, and compared with the same equations written out here
// by hand (no flatsos law) and integrated with a fixed-step RK4. And the paper's arm written with
// order-1 polynomial paths simulates exactly as with constant moment arms.

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include "flatsos/plugin/force/excitation_signal.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"
#include "flatsos/plugin/model/static_equilibrium.hpp"
#include "state_table_column.hpp"

namespace {

namespace fp = flatsos::plugin;
using flatsos::test::column;
using nlohmann::json;

constexpr double kPi = 3.14159265358979323846;

// ---- the model, as numbers typed once and used by both sides ----
constexpr double kMass = 1.5, kCom = 0.17, kInertia = 0.02, kGravity = 9.81;
constexpr double kHeldShoulder = 0.3;  // rad: a coordinate the flexor's path needs, the model lacks
// Flexor length over (X = elbow, Y = shoulder), order 2, OpenSim's term order
// 1, Y, Y^2, X, XY, X^2: r(X) = -(c3 + c4 Y + 2 c5 X) = 0.02 m at X = 0, 0.04 m at 90 degrees.
constexpr std::array<double, 6> kFlexorPath = {0.2949, 0.02, -0.01, -0.023, 0.01, -0.02 / kPi};
constexpr double kExtensorL0 = 0.25, kExtensorArm = -0.02;

struct Muscle {
  double fmax, lopt, lslack, pennation, passive_strain;
};
constexpr std::array<Muscle, 2> kMuscles = {{{800.0, 0.12, 0.17, 0.2, 0.6}, {600.0, 0.11, 0.15, 0.3, 0.5}}};

std::string model_json() {
  json m = {
      {"name", "pennated_elbow"},
      {"bodies", {{{"name", "forearm"}, {"mass_kg", kMass}, {"mass_center_m", {kCom, 0.0, 0.0}},
                   {"inertia_about_mass_center_kg_m2", kInertia}}}},
      {"joints", {{{"name", "elbow"}, {"type", "pin"}, {"parent", "ground"}, {"child", "forearm"},
                   {"location_in_parent_m", {0.0, 0.0, 0.0}}, {"coordinate", "elbow_flexion"},
                   {"range_rad", {-0.1, 2.6}}}}},
      {"muscles",
       {{{"name", "flexor"}, {"max_isometric_force_N", kMuscles[0].fmax}, {"optimal_fiber_length_m", kMuscles[0].lopt},
         {"tendon_slack_length_m", kMuscles[0].lslack}, {"pennation_angle_at_optimal_rad", kMuscles[0].pennation},
         {"passive_fiber_strain_at_one_norm_force", kMuscles[0].passive_strain},
         {"path", {{"coordinates", {"elbow_flexion", "shoulder_elevation"}}, {"order", 2}, {"coefficients", kFlexorPath},
                   {"held_coordinates", {{"shoulder_elevation", kHeldShoulder}}}}}},
        {{"name", "extensor"}, {"max_isometric_force_N", kMuscles[1].fmax}, {"optimal_fiber_length_m", kMuscles[1].lopt},
         {"tendon_slack_length_m", kMuscles[1].lslack}, {"pennation_angle_at_optimal_rad", kMuscles[1].pennation},
         {"passive_fiber_strain_at_one_norm_force", kMuscles[1].passive_strain},
         {"length_at_zero_angles_m", kExtensorL0}, {"moment_arms_m", {{"elbow", kExtensorArm}}}}}}};
  return m.dump();
}

// ---- the hand-written reference ----
namespace ref {

struct Path {
  double length, moment_arm;  // L(q), r(q) = -dL/dq
};
Path path(int j, double q) {
  if (j == 1) return {kExtensorL0 - kExtensorArm * q, kExtensorArm};
  const auto& c = kFlexorPath;
  const double y = kHeldShoulder;
  return {c[0] + c[1] * y + c[2] * y * y + c[3] * q + c[4] * q * y + c[5] * q * q, -(c[3] + c[4] * y + 2.0 * c[5] * q)};
}

double tendon_force(const Muscle& m, double ls) {
  const double k = m.fmax / ((0.04 * m.lslack) * (0.04 * m.lslack));
  return ls > m.lslack ? k * (ls - m.lslack) * (ls - m.lslack) : 0.0;
}
double force_length(const Muscle& m, double lm) {
  const double x = (lm - m.lopt) / (0.56 * m.lopt);
  return std::exp(-x * x);
}
// C2 passive curve: Fmax (e^y - 1 - y - y^2/2) / (e^4 - 1 - 4 - 8), y = 4 (L_M/Lopt - 1)/e0 > 0.
double passive_force(const Muscle& m, double lm) {
  const double y = 4.0 * (lm / m.lopt - 1.0) / m.passive_strain;
  if (y <= 0.0) return 0.0;
  return m.fmax * (std::exp(y) - 1.0 - y - 0.5 * y * y) / (std::exp(4.0) - 13.0);
}
double inverse_force_velocity(const Muscle& m, double z) {
  const double vmax = 10.0 * m.lopt, ah = 0.25, gmax = 1.5;
  if (z <= 1.0) return vmax * (1.0 - z) / (1.0 + z / ah);
  return -(z - 1.0) * (gmax - 1.0) * ah * vmax / ((ah + 1.0) * (gmax - z));
}
double activation_rate(double n, double a) {
  const double beta = 0.01 / 0.04;
  return (beta + (1.0 - beta) * n) / 0.01 * (n - a);
}

// State: q, qd, tendon lengths (2), activations (2).
using State = std::array<double, 6>;
struct Diagnostics {
  double z_min = INFINITY, z_max = -INFINITY, passive_max = 0.0, arm_min = INFINITY, arm_max = -INFINITY, cos_min = 1.0;
};

State rhs(double t, const State& x, const std::function<std::array<double, 2>(double)>& excitation, Diagnostics& d) {
  State dx{};
  const double q = x[0], qd = x[1];
  const std::array<double, 2> n = excitation(t);
  double tau = -kMass * kGravity * kCom * std::cos(q);
  for (int j = 0; j < 2; ++j) {
    const Muscle& m = kMuscles[j];
    const Path p = path(j, q);
    const double ls = x[2 + j], a = x[4 + j];
    const double along = p.length - ls;
    const double h = m.lopt * std::sin(m.pennation);
    const double lm = std::sqrt(along * along + h * h);
    const double cos_phi = along / lm;
    const double force = tendon_force(m, ls);
    const double passive = passive_force(m, lm);
    const double z = (force / cos_phi - passive) / (std::max(a, 1e-4) * m.fmax * force_length(m, lm));
    const double u = inverse_force_velocity(m, z);  // fibre shortening along the fibre
    dx[2 + j] = -p.moment_arm * qd + u / cos_phi;   // dL/dt + u / cos
    dx[4 + j] = activation_rate(n[j], a);
    tau += p.moment_arm * force;
    d.z_min = std::min(d.z_min, z);
    d.z_max = std::max(d.z_max, z);
    d.passive_max = std::max(d.passive_max, passive);
    if (j == 0) d.arm_min = std::min(d.arm_min, p.moment_arm), d.arm_max = std::max(d.arm_max, p.moment_arm);
    d.cos_min = std::min(d.cos_min, cos_phi);
  }
  dx[0] = qd;
  dx[1] = tau / (kInertia + kMass * kCom * kCom);
  return dx;
}

}  // namespace ref

class Sinusoid final : public fp::ExcitationSignal {
 public:
  Sinusoid(double mean, double amplitude, double frequency_hz) : mean_(mean), amplitude_(amplitude), f_(frequency_hz) {}
  double value(double t) const override { return mean_ + amplitude_ * std::sin(2.0 * kPi * f_ * t); }

 private:
  double mean_, amplitude_, f_;
};

}  // namespace

TEST(PostureDependentMuscles, SimbodyMatchesAHandWrittenModelWithPennationAndPassiveForce) {
  const auto model = std::make_shared<const fp::MusculoskeletalModel>(fp::parse_model_json(model_json(), "pennated elbow"));
  ASSERT_FALSE(model->hasConstantMomentArms());
  // The loaded path is the typed polynomial: lengths and moment arms at a few postures.
  for (double q : {0.0, 0.7, kPi / 2, 2.4}) {
    const Eigen::VectorXd qv = Eigen::VectorXd::Constant(1, q);
    const Eigen::MatrixXd R = model->momentArmMatrix(qv);
    for (int j = 0; j < 2; ++j) {
      EXPECT_NEAR(model->musculotendonLength(j, qv), ref::path(j, q).length, 1e-15);
      EXPECT_NEAR(R(0, j), ref::path(j, q).moment_arm, 1e-15);
    }
  }
  EXPECT_NEAR(ref::path(0, kPi / 2).moment_arm, 2.0 * ref::path(0, 0.0).moment_arm, 1e-12);  // doubles by 90 degrees

  // Start at rest in torque balance: the flexor's activation that holds the forearm against
  // gravity and the extensor (bisection on the model's static equilibrium), so the excitations
  // below make the elbow swing about a posture instead of falling through its range.
  const double q0 = 0.8;
  auto net_torque = [&](double flexor_activation) {
    double tau = -kMass * kGravity * kCom * std::cos(q0);
    const std::array<double, 2> a{flexor_activation, 0.3};
    for (int j = 0; j < 2; ++j) {
      const auto& p = model->muscle(j).getParameters();
      const double L = ref::path(j, q0).length;
      tau += ref::path(j, q0).moment_arm * ref::tendon_force(kMuscles[j], fp::static_equilibrium_tendon_length(p, L, a[j]));
    }
    return tau;
  };
  double lo = 0.01, hi = 1.0;
  ASSERT_LT(net_torque(lo), 0.0);
  ASSERT_GT(net_torque(hi), 0.0);
  for (int it = 0; it < 60; ++it) (net_torque(0.5 * (lo + hi)) < 0.0 ? lo : hi) = 0.5 * (lo + hi);
  const Eigen::Vector2d a0(0.5 * (lo + hi), 0.3);
  SimTK::State s = model->defaultState();
  model->setJointAngles(s, Eigen::VectorXd::Constant(1, q0));
  fp::equilibrate_tendons(*model, s, a0);
  const std::array<std::shared_ptr<const Sinusoid>, 2> signals = {std::make_shared<const Sinusoid>(a0[0], 0.6 * a0[0], 1.1),
                                                                  std::make_shared<const Sinusoid>(a0[1], 0.2, 1.7)};
  for (int j = 0; j < 2; ++j) model->muscle(j).setExcitationSignal(s, signals[j]);
  ref::State x{q0, 0.0, 0.0, 0.0, a0[0], a0[1]};
  const Eigen::VectorXd ls0 = model->tendonLengths(s);
  x[2] = ls0[0];
  x[3] = ls0[1];
  // The tendons start in static equilibrium of the hand-written laws too (dL_S/dt = 0 at rest).
  ref::Diagnostics start;
  const ref::State dx0 = ref::rhs(0.0, x, [&](double) { return std::array<double, 2>{a0[0], a0[1]}; }, start);
  EXPECT_NEAR(dx0[2], 0.0, 1e-10);
  EXPECT_NEAR(dx0[3], 0.0, 1e-10);

  fp::SimulationOptions options;
  options.duration_s = 1.0;
  options.accuracy = 1e-10;
  options.report_interval_s = 0.01;
  const fp::SimulationResult sim = fp::simulate(*model, s, options);
  ASSERT_TRUE(sim.finite) << sim.message;

  // RK4 with 1e-6 s steps, reported on the table's times.
  const auto excitation = [&](double t) { return std::array<double, 2>{signals[0]->value(t), signals[1]->value(t)}; };
  const auto t_col = column(sim.states, "time");
  const auto q_col = column(sim.states, "/jointset/elbow/elbow_flexion/value");
  const std::array<std::vector<double>, 2> a_col = {column(sim.states, "/forceset/flexor/activation"),
                                                    column(sim.states, "/forceset/extensor/activation")};
  const std::array<std::vector<double>, 2> ls_col = {column(sim.states, "/forceset/flexor/tendon_length"),
                                                     column(sim.states, "/forceset/extensor/tendon_length")};
  constexpr double kStep = 1e-6;
  ref::Diagnostics diag;
  double t = 0.0, max_q = 0.0, max_a = 0.0, max_ls = 0.0, q_lo = q0, q_hi = q0;
  for (std::size_t r = 0; r < t_col.size(); ++r) {
    while (t < t_col[r] - 0.5 * kStep) {
      const ref::State k1 = ref::rhs(t, x, excitation, diag);
      ref::State y;
      for (int i = 0; i < 6; ++i) y[i] = x[i] + 0.5 * kStep * k1[i];
      const ref::State k2 = ref::rhs(t + 0.5 * kStep, y, excitation, diag);
      for (int i = 0; i < 6; ++i) y[i] = x[i] + 0.5 * kStep * k2[i];
      const ref::State k3 = ref::rhs(t + 0.5 * kStep, y, excitation, diag);
      for (int i = 0; i < 6; ++i) y[i] = x[i] + kStep * k3[i];
      const ref::State k4 = ref::rhs(t + kStep, y, excitation, diag);
      for (int i = 0; i < 6; ++i) x[i] += kStep / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
      t += kStep;
    }
    max_q = std::max(max_q, std::abs(q_col[r] - x[0]));
    q_lo = std::min(q_lo, x[0]);
    q_hi = std::max(q_hi, x[0]);
    for (int j = 0; j < 2; ++j) {
      max_a = std::max(max_a, std::abs(a_col[j][r] - x[4 + j]));
      max_ls = std::max(max_ls, std::abs(ls_col[j][r] - x[2 + j]));
    }
  }
  EXPECT_LE(max_q, 1e-6);
  EXPECT_LE(max_a, 1e-7);
  EXPECT_LE(max_ls, 1e-9);
  // What the comparison covered: a real motion inside the range, a moment arm that changed, the
  // passive force engaged, pennation, and force ratios where the exact force-velocity inverse holds.
  EXPECT_GT(q_hi - q_lo, 0.3);
  EXPECT_GT(q_lo, -0.1);
  EXPECT_LT(q_hi, 2.6);
  EXPECT_GT(diag.arm_max / diag.arm_min, 1.15);
  EXPECT_GT(diag.passive_max, 10.0);
  EXPECT_LT(diag.cos_min, 0.99);
  EXPECT_GE(diag.z_min, 0.0);
  EXPECT_LE(diag.z_max, 1.45);
  std::printf("[posture-dependent] max |dq| %.3g rad, |da| %.3g, |dLS| %.3g m; q in [%.1f, %.1f] deg; flexor arm "
              "%.4f..%.4f m; passive up to %.0f N; z in [%.3f, %.3f]; Simbody %ld steps\n",
              max_q, max_a, max_ls, q_lo * 180 / kPi, q_hi * 180 / kPi, diag.arm_min, diag.arm_max, diag.passive_max,
              diag.z_min, diag.z_max, sim.integrator_steps);
}

TEST(PostureDependentMuscles, ThePapersArmWithOrderOnePolynomialPathsSimulatesIdentically) {
  const std::string path = std::string(FLATSOS_SOURCE_DIR) + "/models/arm_richter_warner.json";
  std::ifstream in(path);
  json arm = json::parse(in);
  // Rewrite every muscle's constant moment arms as OpenSim's order-1 polynomial of
  // (shoulder, elbow): coefficients 1, elbow, shoulder.
  for (auto& m : arm["muscles"]) {
    const double l0 = m["length_at_zero_angles_m"].get<double>();
    double d_shoulder = 0.0, d_elbow = 0.0;
    for (const auto& item : m["moment_arms_m"].items())
      (item.key() == "shoulder" ? d_shoulder : d_elbow) = item.value().get<double>();
    m.erase("length_at_zero_angles_m");
    m.erase("moment_arms_m");
    m["path"] = {{"coordinates", {"shoulder", "elbow"}}, {"order", 1}, {"coefficients", {l0, -d_elbow, -d_shoulder}}};
  }
  const auto constant = fp::MusculoskeletalModel::fromFile(path);
  const auto polynomial = std::make_shared<const fp::MusculoskeletalModel>(fp::parse_model_json(arm.dump(), "arm as polynomials"));
  ASSERT_TRUE(polynomial->hasConstantMomentArms());
  EXPECT_EQ(polynomial->momentArmMatrix(), constant->momentArmMatrix());
  Eigen::VectorXd a0(6);
  a0 << 0.135, 0.040, 0.404, 0.556, 0.414, 0.068;
  std::array<fp::SimulationResult, 2> results;
  for (int k = 0; k < 2; ++k) {
    const fp::MusculoskeletalModel& model = k == 0 ? *constant : *polynomial;
    SimTK::State s = model.defaultState();
    model.setJointAngles(s, Eigen::Vector2d(0.0, 10.0 * kPi / 180.0));
    fp::equilibrate_tendons(model, s, a0);
    Eigen::VectorXd n(6);
    n << 0.3, 0.1, 0.5, 0.4, 0.3, 0.2;
    model.setExcitations(s, n);
    fp::SimulationOptions options;
    options.duration_s = 0.5;
    options.accuracy = 1e-9;
    results[k] = fp::simulate(model, s, options);
    ASSERT_TRUE(results[k].finite);
  }
  ASSERT_EQ(results[0].states.rows.size(), results[1].states.rows.size());
  double worst = 0.0;
  for (std::size_t r = 0; r < results[0].states.rows.size(); ++r)
    for (std::size_t c = 0; c < results[0].states.rows[r].size(); ++c)
      worst = std::max(worst, std::abs(results[0].states.rows[r][c] - results[1].states.rows[r][c]));
  // Round-off only: the order-1 polynomial sums the same terms in another order.
  EXPECT_LE(worst, 1e-12);
  std::printf("[posture-dependent] the arm with order-1 polynomial paths: largest state difference %.3g\n", worst);
}
