#include "flatsos/planner/collocation.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "collocation/hermite_simpson.hpp"
#include "flatness/input_checks.hpp"
#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/planner/numerics/bspline.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "numerics/ipopt_support.hpp"

namespace flatsos::planner {

namespace {

using Ipopt::Number;

// Ipopt's view of the transcription.
class CollocationNlp : public Ipopt::TNLP {
 public:
  CollocationNlp(const detail::HermiteSimpsonProblem& problem, std::vector<double> start)
      : problem_(problem), start_(std::move(start)) {}

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac, Ipopt::Index& nnz_h, IndexStyleEnum& style) override {
    n = problem_.variables();
    m = problem_.constraints();
    nnz_jac = problem_.jacobianNonzeros();
    nnz_h = problem_.hessianNonzeros();
    style = C_STYLE;
    return true;
  }
  bool get_bounds_info(Ipopt::Index, Number* xl, Number* xu, Ipopt::Index, Number* gl, Number* gu) override {
    problem_.bounds(xl, xu, gl, gu);
    return true;
  }
  bool get_starting_point(Ipopt::Index, bool init_x, Number* x, bool, Number*, Number*, Ipopt::Index, bool, Number*) override {
    if (init_x) std::copy(start_.begin(), start_.end(), x);
    return true;
  }
  bool eval_f(Ipopt::Index, const Number* x, bool, Number& f) override {
    f = problem_.objective(x);
    return std::isfinite(f);
  }
  bool eval_grad_f(Ipopt::Index, const Number* x, bool, Number* g) override {
    problem_.objectiveGradient(x, g);
    return true;
  }
  bool eval_g(Ipopt::Index, const Number* x, bool, Ipopt::Index m, Number* g) override {
    problem_.constraintValues(x, g);
    for (Ipopt::Index r = 0; r < m; ++r)
      if (!std::isfinite(g[r])) return false;
    return true;
  }
  bool eval_jac_g(Ipopt::Index, const Number* x, bool, Ipopt::Index, Ipopt::Index nnz, Ipopt::Index* irow, Ipopt::Index* jcol, Number* values) override {
    if (!values) {
      for (Ipopt::Index k = 0; k < nnz; ++k) irow[k] = problem_.jacobianRows()[k], jcol[k] = problem_.jacobianColumns()[k];
      return true;
    }
    problem_.jacobianValues(x, values);
    return true;
  }
  bool eval_h(Ipopt::Index, const Number* x, bool, Number objective_factor, Ipopt::Index, const Number* lambda, bool, Ipopt::Index nnz,
              Ipopt::Index* irow, Ipopt::Index* jcol, Number* values) override {
    if (!values) {
      for (Ipopt::Index k = 0; k < nnz; ++k) irow[k] = problem_.hessianRows()[k], jcol[k] = problem_.hessianColumns()[k];
      return true;
    }
    problem_.hessianValues(x, objective_factor, lambda, values);
    return true;
  }
  void finalize_solution(Ipopt::SolverReturn, Ipopt::Index n, const Number* x, const Number*, const Number*, Ipopt::Index,
                         const Number*, const Number*, Number, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    x_.assign(x, x + n);
  }

  std::vector<double> x_;

 private:
  const detail::HermiteSimpsonProblem& problem_;
  std::vector<double> start_;
};

// The start: the flat outputs held at their initial values, Y(t) = Y(0), mapped to muscle states
// by the exact inverse map (consistent dynamics, exact joint torques), the excitations,
// activations and fibre velocities clipped into their bounds. Where a muscle leaves its domain
// (a slack tendon), the transcription's torque-split start is kept for it. Any start reaches the
// same optimum (tested); this one took 126 Ipopt iterations on the paper's problem (K = 100),
// the torque split 274, a static-optimization LP start 163.
std::vector<double> constant_flat_output_start(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                               const JointPath& path, const MuscleState& initial,
                                               const detail::HermiteSimpsonProblem& problem) {
  using H = detail::HermiteSimpsonProblem;
  std::vector<double> x(problem.variables());
  problem.startingPoint(x.data());
  Jet Y_jet = Eigen::MatrixXd::Zero(flat.numFlatOutputs(), 3);
  Y_jet.col(0) = flat.forward(workspace, initial).Y.col(0);
  for (int i = 1; i < problem.points(); ++i) {
    const MusclePoint mp = flat.inverse(workspace, path.jet(problem.samples().time_s[i], 5), Y_jet);
    for (int j = 0; j < problem.muscles(); ++j) {
      const auto& mu = problem.muscle(j);
      const auto& p = mu.parameters;
      const double a = mp.activation[j], n = mp.excitation[j], u = mp.shortening_velocity_m_per_s[j];
      const double s = (mp.tendon_length_m[j] - p.tendon_slack_length_m) / (p.tendon_strain_at_max_force * p.tendon_slack_length_m);
      if (!(std::isfinite(a) && std::isfinite(n) && std::isfinite(u) && std::isfinite(s))) continue;
      x[problem.index(i, j, H::kStretch)] = std::max(s, problem.stretchAtForce(j, mu.reserve_N));
      x[problem.index(i, j, H::kActivation)] = std::clamp(a, mu.min_activation, 1.0);
      x[problem.index(i, j, H::kExcitation)] = std::clamp(n, p.model->minimumExcitation(p), 1.0);
      if (i < problem.points() - 1)  // rest at T is fixed
        x[problem.index(i, j, H::kVelocity)] = std::min(u / p.max_shortening_velocity_m_per_s(), 0.9);
    }
  }
  return x;
}

struct IpoptOutcome {
  bool solved = false, infeasible = false;
  std::string solver_status;
  std::string linear_solver;
  int iterations = 0;
  std::vector<double> x;
};

// Ipopt's objective scaling: a cost in N s is O(100-1000), scaled to O(1)-O(10) per unit of time
// and weight; a dimensionless integrand (powers of n, a, F / Fmax <= 1) per unit of time and
// muscle.
double objective_scaling(const Effort& effort, double duration_s, int muscles) {
  if (const std::optional<Eigen::VectorXd> w = effort.tendonForceWeights())
    return 1.0 / (duration_s * std::max(w->sum(), 1e-12) * 10.0);
  return 1.0 / (duration_s * muscles);
}

IpoptOutcome run_ipopt(const detail::HermiteSimpsonProblem& problem, std::vector<double> start, const CollocationOptions& o,
                       double objective_scaling_factor) {
  Ipopt::SmartPtr<CollocationNlp> nlp = new CollocationNlp(problem, std::move(start));
  auto app = detail::make_ipopt(o.tolerance, o.max_iterations, *nlp, /*rows_in_time_order=*/true);
  app->Options()->SetNumericValue("obj_scaling_factor", objective_scaling_factor);
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::SmartPtr<Ipopt::TNLP>(GetRawPtr(nlp)));
  IpoptOutcome out;
  out.solver_status = detail::ipopt_status_name(status);
  out.linear_solver = ipopt_linear_solver_name(app.linear_solver);
  if (Ipopt::SmartPtr<Ipopt::SolveStatistics> stats = app->Statistics(); IsValid(stats)) out.iterations = stats->IterationCount();
  out.solved = detail::ipopt_solved(status) && static_cast<int>(nlp->x_.size()) == problem.variables();
  out.infeasible = detail::ipopt_infeasible(status);
  out.x = std::move(nlp->x_);
  return out;
}

void validate(const FlatOutputMap& flat, const JointPath& path, const MuscleState* initial, const Eigen::VectorXd& reserves,
              const CollocationOptions& o, bool free_path) {
  const int m = flat.numMuscles();
  if (!(path.duration_s > 0.0) || !std::isfinite(path.duration_s))
    throw std::invalid_argument("collocation: the joint path's duration must be > 0 s");
  if (path.numJoints() != flat.numJoints())
    throw std::invalid_argument("collocation: the joint path has " + std::to_string(path.numJoints()) +
                                " joint polynomials, the model " + std::to_string(flat.numJoints()) + " joints");
  if (initial) detail::require_initial_muscle_state(flat, *initial);
  detail::require_reserves(reserves, m);
  // The transcription's derivatives are written for fibres along the tendon without passive
  // force, and a free path's for constant moment arms: refuse the others rather than solve a
  // different problem.
  if (free_path && !flat.hasConstantMomentArms())
    throw std::invalid_argument("collocation: model '" + flat.model().description().name +
                                "' has posture-dependent moment arms, which the collocation reference models only along a prescribed path");
  for (const auto& muscle : flat.model().description().muscles) {
    const muscles::MuscleParameters& p = muscle.parameters;
    if (p.pennation_angle_at_optimal_rad != 0.0 || p.hasPassiveFiberForce())
      throw std::invalid_argument("collocation: muscle '" + p.name +
                                  "' has pennation or passive fibre force, which the collocation reference does not model");
    // Newton's method stalls on a law whose slope jumps (measured on Thelen's muscles: 3000
    // Ipopt iterations without convergence; either kink removed, 46-48).
    if (const std::string kinks = p.model->slopeJumps(); !kinks.empty())
      throw std::invalid_argument("collocation: muscle '" + p.name + "' follows the " + p.model->name() +
                                  " model, whose " + kinks +
                                  "; the collocation reference needs laws with continuous slopes, as direct "
                                  "collocation tools advise");
    if (p.fiber_damping != 0.0 || p.model->scalesMaxVelocityWithActivation())
      throw std::invalid_argument("collocation: muscle '" + p.name +
                                  "' has fibre damping or a maximum velocity that depends on activation, which the "
                                  "collocation reference does not model");
  }
  if (o.effort || o.effort_weights.size() > 0) {
    try {
      if (o.effort)
        o.effort->validate(m);
      else
        TendonForceEffort(o.effort_weights).validate(m);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("collocation: ") + e.what());
    }
  }
  if (o.mesh_intervals < 1) throw std::invalid_argument("collocation: mesh_intervals must be >= 1");
  if (!(o.mesh_interval_growth > 0.0) || !std::isfinite(o.mesh_interval_growth))
    throw std::invalid_argument("collocation: mesh_interval_growth must be finite and > 0 (1: uniform intervals)");
  if (!(o.min_activation >= 0.0 && o.min_activation < 1.0))
    throw std::invalid_argument("collocation: min_activation must be in [0, 1)");
  if (!(o.tolerance > 0.0)) throw std::invalid_argument("collocation: tolerance must be > 0");
  if (o.max_iterations < 1) throw std::invalid_argument("collocation: max_iterations must be >= 1");
}

}  // namespace

namespace detail {

PathSamples sample_path(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const JointPath& path,
                        int intervals, double growth) {
  const int P = 2 * intervals + 1, m = flat.numMuscles();
  PathSamples samples;
  if (growth == 1.0) {
    // Uniform points as they always were: Ipopt's path on the arm's free path is that sensitive
    // (the same points as mesh points and their midpoints, apart in the last bits: 270 iterations
    // instead of 116, the same optimum).
    samples.time_s = Eigen::VectorXd::LinSpaced(P, 0.0, path.duration_s);
  } else {
    const std::vector<double> mesh = geometric_breakpoints(intervals, path.duration_s, growth);
    samples.time_s.resize(P);
    for (int k = 0; k < intervals; ++k) {
      samples.time_s[2 * k] = mesh[static_cast<std::size_t>(k)];
      samples.time_s[2 * k + 1] = 0.5 * (mesh[static_cast<std::size_t>(k)] + mesh[static_cast<std::size_t>(k) + 1]);
    }
    samples.time_s[P - 1] = path.duration_s;
  }
  samples.musculotendon_length_m.resize(m, P);
  samples.lengthening_rate_m_per_s.resize(m, P);
  samples.torque_N_m.resize(flat.numJoints(), P);
  const bool posture_dependent = !flat.hasConstantMomentArms();
  samples.moment_arms_m = posture_dependent ? flat.momentArms(path.jet(0.0, 1).col(0)) : flat.A();
  samples.q_rad.resize(flat.numJoints(), P);
  samples.qd_rad_per_s.resize(flat.numJoints(), P);
  samples.qdd_rad_per_s2.resize(flat.numJoints(), P);
  for (int i = 0; i < P; ++i) {
    const Jet q = path.jet(samples.time_s[i], 3);
    samples.q_rad.col(i) = q.col(0);
    samples.qd_rad_per_s.col(i) = q.col(1);
    samples.qdd_rad_per_s2.col(i) = q.col(2);
    samples.torque_N_m.col(i) = flat.torque(workspace, q.col(0), q.col(1), q.col(2));
    if (posture_dependent) samples.moment_arms_at.push_back(flat.momentArms(q.col(0)));
    for (int j = 0; j < m; ++j) {
      const muscles::SecondOrderJet L = flat.pathLengthJet(j, q);
      samples.musculotendon_length_m(j, i) = L.value;
      samples.lengthening_rate_m_per_s(j, i) = L.rate;
    }
  }
  return samples;
}

FreeJoints free_joints(const FlatOutputMap& flat, const JointPath& path) {
  const Jet start = path.jet(0.0, 3), end = path.jet(path.duration_s, 3);
  if (end.rightCols(2).cwiseAbs().maxCoeff() > 1e-9)
    throw std::invalid_argument("collocation: a free joint path ends at rest, but the given path ends with joint speeds or "
                                "accelerations up to " + std::to_string(end.rightCols(2).cwiseAbs().maxCoeff()));
  FreeJoints fj;
  fj.dynamics = &flat.model().pinTree();
  fj.length_at_zero_angles_m.resize(flat.numMuscles());
  for (int j = 0; j < flat.numMuscles(); ++j)
    fj.length_at_zero_angles_m[j] = flat.model().musculotendonLength(j, Eigen::VectorXd::Zero(flat.numJoints()));
  fj.start_q_rad = start.col(0);
  fj.start_qd_rad_per_s = start.col(1);
  fj.end_q_rad = end.col(0);
  return fj;
}

std::vector<CollocationMuscle> collocation_muscles(const FlatOutputMap& flat, const MuscleState& initial,
                                                   const Eigen::VectorXd& reserves_N, double min_activation) {
  std::vector<CollocationMuscle> muscles(flat.numMuscles());
  for (int j = 0; j < flat.numMuscles(); ++j) {
    const auto& p = flat.model().muscle(j).getParameters();
    auto& mu = muscles[j];
    mu.parameters = p;
    mu.reserve_N = reserves_N[j];
    mu.min_activation = min_activation > 0.0 ? min_activation : p.activation_floor;
    mu.initial_stretch = (initial.tendon_length_m[j] - p.tendon_slack_length_m) / (p.tendon_strain_at_max_force * p.tendon_slack_length_m);
    mu.initial_activation = initial.activation[j];
  }
  return muscles;
}

}  // namespace detail

Eigen::VectorXd flat_output_effort_weights(const FlatOutputMap& flat) {
  return flat.E().transpose() * Eigen::VectorXd::Ones(flat.numFlatOutputs());
}

namespace {

// The problems: along the path from `initial` to rest, along it with the muscles free at both
// ends (initial null), or (free) with the path free between its ends.
CollocationResult solve_collocation(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const JointPath& path,
                                    const MuscleState* initial, const Eigen::VectorXd& reserves_N,
                                    const CollocationOptions& o, bool free) {
  validate(flat, path, initial, reserves_N, o, free);
  const Stopwatch setup;
  const int m = flat.numMuscles(), N = flat.numJoints();
  const std::shared_ptr<const Effort> effort = o.effort                       ? o.effort
                                               : o.effort_weights.size() > 0 ? std::make_shared<TendonForceEffort>(o.effort_weights)
                                                                             : flat.effort();
  detail::PathSamples samples = detail::sample_path(flat, workspace, path, o.mesh_intervals, o.mesh_interval_growth);
  MuscleState none;  // free muscle ends: no initial state to read
  none.tendon_length_m = Eigen::VectorXd::Zero(m), none.activation = Eigen::VectorXd::Zero(m);
  std::vector<detail::CollocationMuscle> muscles =
      detail::collocation_muscles(flat, initial ? *initial : none, reserves_N, o.min_activation);

  std::optional<detail::FreeJoints> free_path;
  if (free) {
    free_path = detail::free_joints(flat, path);
  } else if (initial) {
    // The initial state fixes every tendon force at t = 0; the path must start with the joint
    // accelerations they produce, or no plan exists along it.
    Eigen::VectorXd F0(m);
    for (int j = 0; j < m; ++j)
      F0[j] = muscles::tendon_force(flat.model().muscle(j).getParameters(), initial->tendon_length_m[j]);
    const Eigen::VectorXd torque_gap = samples.moment_arms_m * F0 - samples.torque_N_m.col(0);
    if (torque_gap.cwiseAbs().maxCoeff() > 1e-6 * (1.0 + samples.torque_N_m.col(0).cwiseAbs().maxCoeff())) {
      std::ostringstream why;
      why << "collocation: the joint path does not start with the accelerations of the initial state (the muscles' "
             "torques differ from the path's inverse dynamics at t = 0 by up to "
          << torque_gap.cwiseAbs().maxCoeff() << " N m)";
      throw std::invalid_argument(why.str());
    }
  }
  const detail::HermiteSimpsonProblem problem(std::move(muscles), std::move(samples), effort, std::move(free_path),
                                              initial == nullptr);

  CollocationResult result;
  result.mesh_intervals = o.mesh_intervals;
  result.variables = problem.variables();
  result.constraints = problem.constraints();
  result.setup_seconds = setup.seconds();

  const Stopwatch solve;
  std::vector<double> start(static_cast<std::size_t>(problem.variables()));
  if (initial) start = constant_flat_output_start(flat, workspace, path, *initial, problem);
  else problem.startingPoint(start.data());
  const IpoptOutcome outcome = run_ipopt(problem, std::move(start), o, objective_scaling(*effort, path.duration_s, m));
  result.solve_seconds = solve.seconds();
  result.solver_status = outcome.solver_status;
  result.linear_solver = outcome.linear_solver;
  result.iterations = outcome.iterations;
  const std::string what = free ? "with a free joint path" : initial ? "along this joint path" : "along this motion";
  if (outcome.solved) {
    result.status = SolveStatus::Solved;
  } else if (outcome.infeasible) {
    result.status = SolveStatus::Infeasible;
    result.message = "collocation: no excitations " + what + " meet the reserves and bounds (Ipopt: " +
                     result.solver_status + ")";
    return result;
  } else {
    result.status = SolveStatus::Failed;
    result.message = "collocation " + what + ": Ipopt did not converge (" + result.solver_status + ")";
    return result;
  }
  const double* x = outcome.x.data();
  const int P = problem.points();
  result.cost = problem.objective(x);
  result.cost_unit = effort->unit();
  result.cost_N_s = result.cost;
  result.time_s = problem.samples().time_s;
  result.tendon_force_N.resize(m, P);
  result.tendon_length_m.resize(m, P);
  result.activation.resize(m, P);
  result.excitation.resize(m, P);
  result.shortening_velocity_m_per_s.resize(m, P);
  result.activation_rate_per_s.resize(m, P);
  result.joint_angle_rad.resize(N, P);
  result.joint_speed_rad_per_s.resize(N, P);
  result.joint_acceleration_rad_per_s2.resize(N, P);
  using H = detail::HermiteSimpsonProblem;
  for (int i = 0; i < P; ++i) {
    for (int j = 0; j < m; ++j) {
      result.tendon_force_N(j, i) = problem.tendonForce(x, i, j);
      result.tendon_length_m(j, i) = problem.tendonLength(x, i, j);
      result.activation(j, i) = x[problem.index(i, j, H::kActivation)];
      result.excitation(j, i) = x[problem.index(i, j, H::kExcitation)];
      result.activation_rate_per_s(j, i) = problem.activationRate(x, i, j);
      result.shortening_velocity_m_per_s(j, i) = problem.shorteningVelocity(x, i, j);
    }
    for (int r = 0; r < N; ++r) {
      result.joint_angle_rad(r, i) = problem.joint(x, i, r, H::kAngle);
      result.joint_speed_rad_per_s(r, i) = problem.joint(x, i, r, H::kSpeed);
      result.joint_acceleration_rad_per_s2(r, i) = problem.joint(x, i, r, H::kAcceleration);
    }
  }
  return result;
}

}  // namespace

CollocationResult solve_collocation_along_path(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                               const JointPath& path, const MuscleState& initial,
                                               const Eigen::VectorXd& reserves_N, const CollocationOptions& o) {
  return solve_collocation(flat, workspace, path, &initial, reserves_N, o, false);
}

CollocationResult solve_collocation_along_motion(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                                 const JointPath& path, const Eigen::VectorXd& reserves_N,
                                                 const CollocationOptions& o) {
  return solve_collocation(flat, workspace, path, nullptr, reserves_N, o, false);
}

CollocationResult solve_collocation_free_path(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                              const JointPath& start_path, const MuscleState& initial,
                                              const Eigen::VectorXd& reserves_N, const CollocationOptions& o) {
  return solve_collocation(flat, workspace, start_path, &initial, reserves_N, o, true);
}

}  // namespace flatsos::planner
