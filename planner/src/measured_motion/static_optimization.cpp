#include "flatsos/planner/static_optimization.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/muscles/static_equilibrium.hpp"
#include "flatsos/muscles/thelen2003_opensim2_muscle.hpp"
#include "flatsos/planner/separable_power_program.hpp"
#include "flatsos/plugin/io/sto_file.hpp"
#include "flatsos/plugin/stopwatch.hpp"

namespace flatsos::planner {

namespace fm = flatsos::muscles;

namespace {

// OpenSim 2.x's generic force-velocity factor of the normalized shortening speed (Muscle.cpp).
double generic_force_velocity(double shortening_in_max_velocities) {
  return 1.8 - 1.8 / (1.0 + std::exp((0.04 - shortening_in_max_velocities) / 0.18));
}

double opensim2_strength_N(const fm::MuscleParameters& p, double length_m, double lengthening_m_per_s) {
  const double tendon_m = fm::static_equilibrium_tendon_length(p, length_m, 1.0);
  const double isometric_N = fm::tendon_force(p, tendon_m);
  const double v = std::cos(p.pennation_angle_at_optimal_rad) * -lengthening_m_per_s / p.max_shortening_velocity_m_per_s();
  return isometric_N * generic_force_velocity(v);
}

double rigid_tendon_strength_N(const fm::MuscleParameters& p, double length_m, double lengthening_m_per_s) {
  const fm::FiberGeometry fiber = fm::fiber_geometry(p, length_m - p.tendon_slack_length_m);
  const double shortening_m_per_s = -fiber.cos_pennation * lengthening_m_per_s;  // along the fibre
  return p.max_isometric_force_N * p.model->activeForceLength(p, fiber.length_m).value *
         p.model->forceVelocity(p, shortening_m_per_s).value * fiber.cos_pennation;
}

// A muscle's length, lengthening rate and moment arms (per joint) at q, qd: from its geometry
// when the model carries it (each frame stands alone: no smoothness is needed, so OpenSim's own
// path is used), from its fitted polynomial otherwise.
struct PathAtFrame {
  double length_m = 0.0, lengthening_m_per_s = 0.0;
};
PathAtFrame path_at_frame(const plugin::MusculoskeletalModel& model, int j, const Eigen::VectorXd& q,
                          const Eigen::VectorXd& qd, Eigen::Ref<Eigen::VectorXd> arms_m) {
  const fm::MusculotendonPath& path = model.musclePath(j);
  const auto& geometry = model.description().muscles[static_cast<std::size_t>(j)].path_geometry;
  PathAtFrame out;
  if (!geometry) {
    path.momentArms(q.data(), arms_m.data());
    out.length_m = path.length(q.data());
    out.lengthening_m_per_s = -arms_m.dot(qd);  // dL/dt = -r^T qd
    return out;
  }
  const std::vector<fm::PathCoordinate>& coordinates = path.coordinates();
  double x[fm::LengthPolynomial::kMaxDimension], arms[fm::LengthPolynomial::kMaxDimension],
      gradient[fm::LengthPolynomial::kMaxDimension];
  for (std::size_t k = 0; k < coordinates.size(); ++k)
    x[k] = coordinates[k].held() ? coordinates[k].held_value_rad : q[coordinates[k].joint];
  out.length_m = geometry->length_m(x);
  geometry->momentArms(x, arms);
  geometry->lengthGradient(x, gradient);
  arms_m.setZero();
  for (std::size_t k = 0; k < coordinates.size(); ++k) {
    if (coordinates[k].held()) continue;
    arms_m[coordinates[k].joint] = arms[k];
    out.lengthening_m_per_s += gradient[k] * qd[coordinates[k].joint];
  }
  return out;
}

MuscleStrengthRule default_rule(const plugin::MusculoskeletalModel& model) {
  for (const auto& muscle : model.description().muscles)
    if (muscle.parameters.model->name() != fm::Thelen2003OpenSim2Muscle::kName) return MuscleStrengthRule::RigidTendon;
  return MuscleStrengthRule::OpenSim2;
}

// The spline of each joint's coordinate, in joint order.
std::vector<const plugin::NaturalQuinticSpline*> joint_splines(const plugin::MusculoskeletalModel& model,
                                                               const plugin::ProcessedCoordinates& motion) {
  std::vector<const plugin::NaturalQuinticSpline*> out;
  for (const auto& joint : model.description().joints) {
    const std::string& name = joint.coordinateName();
    bool found = false;
    for (std::size_t k = 0; k < motion.names.size() && !found; ++k)
      if (motion.names[k] == name) out.push_back(&motion.splines[k]), found = true;
    if (!found) throw std::invalid_argument("static optimization: the motion has no column for the coordinate '" + name + "'");
  }
  return out;
}

// The effort as exponent and per-muscle weights of a^p (stress: of (a G / Fmax)^p, so the
// weights are scaled per frame by (G / Fmax)^p); `stress` says which.
struct PowerTerms {
  double exponent = 2.0;
  Eigen::VectorXd weights;
  bool stress = false;
};
PowerTerms power_terms(const plugin::MusculoskeletalModel& model, const StaticOptimizationOptions& o) {
  const int m = model.numMuscles();
  PowerTerms out;
  if (!o.effort) {
    out.exponent = o.activation_exponent;
    out.weights = o.weights.size() == m ? o.weights : Eigen::VectorXd::Ones(m);
    return out;
  }
  o.effort->validate(m);
  const auto* power = dynamic_cast<const PowerEffort*>(o.effort.get());
  if (!power || power->quantity() == PowerEffort::Quantity::Excitation || !(power->exponent() > 1.0))
    throw std::invalid_argument("static optimization: effort '" + o.effort->name() +
                                "' does not fit: it takes a power > 1 of the activations or of the tendon stress "
                                "(excitations need the activation dynamics of the inverse problem)");
  out.exponent = power->exponent();
  out.stress = power->quantity() == PowerEffort::Quantity::TendonStress;
  out.weights.resize(m);
  for (int j = 0; j < m; ++j) {  // the term at a unit quantity is the weight
    const fm::MuscleParameters& p = model.description().muscles[static_cast<std::size_t>(j)].parameters;
    out.weights[j] = power->muscleTerm(j, p, p.max_isometric_force_N, 1.0, 1.0).value;
  }
  if (!(out.weights.array() > 0.0).all()) throw std::invalid_argument("static optimization: the effort's weights must be > 0");
  return out;
}

void validate(const plugin::MusculoskeletalModel& model, const StaticOptimizationOptions& o) {
  if (!(o.activation_exponent > 1.0) || !std::isfinite(o.activation_exponent))
    throw std::invalid_argument("static optimization: activation_exponent must be a finite number > 1");
  if (o.weights.size() != 0 && o.weights.size() != model.numMuscles())
    throw std::invalid_argument("static optimization: weights need one entry per muscle (" +
                                std::to_string(model.numMuscles()) + ")");
  if (o.weights.size() != 0 && !(o.weights.array() > 0.0).all())
    throw std::invalid_argument("static optimization: weights must be > 0");
  if (!(o.reserve_optimal_torque_N_m >= 0.0) || !std::isfinite(o.reserve_optimal_torque_N_m))
    throw std::invalid_argument("static optimization: reserve_optimal_torque_N_m must be a finite number >= 0");
}

}  // namespace

Eigen::VectorXd muscle_strength_N(const plugin::MusculoskeletalModel& model, MuscleStrengthRule rule,
                                  const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  Eigen::MatrixXd arms(model.numJoints(), model.numMuscles());
  return muscle_strength_N(model, rule, q, qd, arms);
}

Eigen::VectorXd muscle_strength_N(const plugin::MusculoskeletalModel& model, MuscleStrengthRule rule,
                                  const Eigen::VectorXd& q, const Eigen::VectorXd& qd, Eigen::MatrixXd& moment_arms_m) {
  const int m = model.numMuscles();
  moment_arms_m.resize(model.numJoints(), m);
  Eigen::VectorXd G(m);
  for (int j = 0; j < m; ++j) {
    const fm::MuscleParameters& p = model.description().muscles[static_cast<std::size_t>(j)].parameters;
    const PathAtFrame path = path_at_frame(model, j, q, qd, moment_arms_m.col(j));
    G[j] = rule == MuscleStrengthRule::OpenSim2 ? opensim2_strength_N(p, path.length_m, path.lengthening_m_per_s)
                                                : rigid_tendon_strength_N(p, path.length_m, path.lengthening_m_per_s);
  }
  return G;
}

plugin::ProcessedCoordinates read_motion_for(const plugin::MusculoskeletalModel& model, const std::string& motion_file,
                                             double cutoff_hz) {
  return plugin::process_coordinates_like_opensim(plugin::read_sto(motion_file), cutoff_hz, [&](const std::string& column) {
    for (const auto& joint : model.description().joints)
      if (joint.coordinateName() == column) return !joint.isSlider();
    return true;  // a column the model does not use: read as an angle, never used
  });
}

StaticOptimizationResult static_optimization(const plugin::MusculoskeletalModel& model,
                                             const plugin::ProcessedCoordinates& motion,
                                             const StaticOptimizationOptions& o) {
  validate(model, o);
  const Stopwatch wall;
  const std::vector<const plugin::NaturalQuinticSpline*> splines = joint_splines(model, motion);
  const int n = model.numJoints(), m = model.numMuscles(), frames = static_cast<int>(motion.report_times_s.size());
  const bool reserves = o.reserve_optimal_torque_N_m > 0.0;
  StaticOptimizationResult out;
  out.strength_rule = o.strength_rule.value_or(default_rule(model));
  out.reserve_optimal_torque_N_m = o.reserve_optimal_torque_N_m;
  out.time_s = motion.report_times_s;
  out.activation.setZero(frames, m);
  out.tendon_force_N.setZero(frames, m);
  out.reserve_torque_N_m.setZero(frames, n);
  out.effort.setZero(frames);

  const PowerTerms effort = power_terms(model, o);
  SeparablePowerProgram program;
  const int variables = m + (reserves ? n : 0);
  program.exponent = effort.exponent;
  program.weights = Eigen::VectorXd::Ones(variables);
  program.lower = Eigen::VectorXd::Zero(variables);
  program.upper = Eigen::VectorXd::Ones(variables);
  if (reserves) {
    program.lower.tail(n).setConstant(-INFINITY);
    program.upper.tail(n).setConstant(INFINITY);
  }
  program.B.setZero(n, variables);
  if (reserves) program.B.rightCols(n) = o.reserve_optimal_torque_N_m * Eigen::MatrixXd::Identity(n, n);
  plugin::ModelWorkspace workspace = model.makeWorkspace();
  Eigen::VectorXd q(n), qd(n), qdd(n), tau(n);
  Eigen::MatrixXd moment_arms(n, m);
  for (int f = 0; f < frames; ++f) {
    const double t = motion.report_times_s[static_cast<std::size_t>(f)];
    for (int i = 0; i < n; ++i) {
      const plugin::NaturalQuinticSpline& s = *splines[static_cast<std::size_t>(i)];
      q[i] = s.value(t), qd[i] = s.firstDerivative(t), qdd[i] = s.secondDerivative(t);
    }
    model.inverseDynamics(workspace, q, qd, qdd, tau);
    const Eigen::VectorXd G = muscle_strength_N(model, out.strength_rule, q, qd, moment_arms);
    program.B.leftCols(m) = moment_arms * G.asDiagonal();
    for (int j = 0; j < m; ++j) {
      const double Fmax = model.description().muscles[static_cast<std::size_t>(j)].parameters.max_isometric_force_N;
      program.weights[j] = effort.weights[j] * (effort.stress ? std::pow(std::abs(G[j]) / Fmax, effort.exponent) : 1.0);
      if (!(program.weights[j] > 0.0)) program.weights[j] = 1e-300;  // a muscle without strength here: free, and useless
    }
    program.b = tau;
    const SeparablePowerSolution s = solve_separable_power_program(program);
    if (!s.solved) {
      const std::string joint = s.worst_row >= 0 && s.worst_row < n
                                    ? model.description().joints[static_cast<std::size_t>(s.worst_row)].coordinateName()
                                    : std::string("?");
      out.failures.push_back(
          "t = " + std::to_string(t) + " s: " +
          (s.infeasible ? "the muscles cannot produce the torque about '" + joint + "' the motion needs (" + s.message + ")" +
                              (reserves ? "" : "; add reserve actuators (reserve_optimal_torque_N_m) to see by how much")
                        : "the optimization did not converge at '" + joint + "' (" + s.message + ")"));
    }
    out.activation.row(f) = s.x.head(m).transpose();
    out.tendon_force_N.row(f) = (s.x.head(m).array() * G.array()).transpose();
    if (reserves) out.reserve_torque_N_m.row(f) = (o.reserve_optimal_torque_N_m * s.x.tail(n)).transpose();
    out.effort[f] = s.objective;
  }
  out.wall_seconds = wall.seconds();
  return out;
}

namespace {
plugin::StoTable result_table(const plugin::MusculoskeletalModel& model, const StaticOptimizationResult& r,
                              const std::string& name, const Eigen::MatrixXd& muscles, double reserve_scale) {
  plugin::StoTable t;
  t.name = name;
  t.columns = {"time"};
  for (const auto& muscle : model.description().muscles) t.columns.push_back(muscle.parameters.name);
  const bool reserves = r.reserve_optimal_torque_N_m > 0.0;  // the same columns whether used or not
  if (reserves)
    for (const auto& joint : model.description().joints) t.columns.push_back(joint.coordinateName() + "_reserve");
  for (std::size_t f = 0; f < r.time_s.size(); ++f) {
    std::vector<double> row = {r.time_s[f]};
    for (Eigen::Index j = 0; j < muscles.cols(); ++j) row.push_back(muscles(static_cast<Eigen::Index>(f), j));
    if (reserves)
      for (Eigen::Index i = 0; i < r.reserve_torque_N_m.cols(); ++i)
        row.push_back(r.reserve_torque_N_m(static_cast<Eigen::Index>(f), i) * reserve_scale);
    t.rows.push_back(std::move(row));
  }
  return t;
}
}  // namespace

plugin::StoTable static_optimization_activation_table(const plugin::MusculoskeletalModel& model,
                                                      const StaticOptimizationResult& r) {
  // A reserve's "activation" is its control: torque / optimal torque.
  const double control_per_N_m = r.reserve_optimal_torque_N_m > 0.0 ? 1.0 / r.reserve_optimal_torque_N_m : 0.0;
  return result_table(model, r, "Static Optimization", r.activation, control_per_N_m);
}

plugin::StoTable static_optimization_force_table(const plugin::MusculoskeletalModel& model,
                                                 const StaticOptimizationResult& r) {
  return result_table(model, r, "Static Optimization", r.tendon_force_N, 1.0);
}

}  // namespace flatsos::planner
