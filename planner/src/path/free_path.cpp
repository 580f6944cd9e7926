#include "path/free_path.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>

#include "bounds/bound_rows.hpp"
#include "bounds/sequential_lp.hpp"
#include "path/joint_path_nlp.hpp"
#include "path/value_function.hpp"
#include "path/path_rows.hpp"

namespace flatsos::planner::detail {

namespace {

constexpr double kFirstStep_rad = 0.05;       // the first quasi-Newton step's largest coefficient change
constexpr double kArmijo = 1e-4;
constexpr int kMaxBacktracks = 12;
// Ipopt's (scaled) optimality tolerance per round. The path stage only has to find the path: the
// plan along it is solved and certified anew, so the barrier's last decades bought nothing there
// (1e-8: 156 iterations on the arm, 1e-6: 86, at 186.5849 against 186.5847 N s; later 1e-6: 558
// iterations over seven configurations, 1e-5: 529, every certified plan the same to 1e-6,
// docs/method/free_path.md).
constexpr double kNewtonTolerance = 1e-5;

// BFGS on V(c) at the current points, from `at` (evaluated there); its inverse-Hessian estimate
// H carries over between exchange rounds. Returns the number of accepted steps; `at` ends at the
// last accepted point. A trial whose plan fails (rows not met, the muscles' domain left) counts
// as V = infinity: the line search backs off.
struct QuasiNewton {
  Eigen::MatrixXd H;
  bool scaled = false;  // H estimates V's curvature (after the first update); before, steps are normalized
};

int minimize(ValueFunction& V, QuasiNewton& qn, Evaluation& at, double relative_tolerance, int max_iterations) {
  const Eigen::Index n = at.c.size();
  if (qn.H.rows() != n) qn.H = Eigen::MatrixXd::Identity(n, n);
  int steps = 0, small = 0;
  for (int it = 0; it < max_iterations && n > 0; ++it) {
    Eigen::VectorXd d = -qn.H * at.gradient;
    if (!(at.gradient.dot(d) < 0.0)) {
      qn.H.setIdentity();
      qn.scaled = false;
      d = -at.gradient;
    }
    const double largest = d.cwiseAbs().maxCoeff();
    if (!(largest > 0.0)) break;
    if (!qn.scaled) d *= kFirstStep_rad / largest;
    const double slope = at.gradient.dot(d);
    double alpha = 1.0;
    Evaluation trial;
    bool accepted = false;
    for (int b = 0; b < kMaxBacktracks; ++b, alpha *= 0.25) {
      trial = V(at.c + alpha * d, at);
      if (trial.ok && trial.cost_N_s <= at.cost_N_s + kArmijo * alpha * slope) {
        accepted = true;
        break;
      }
    }
    if (!accepted) break;
    const Eigen::VectorXd s = trial.c - at.c, y = trial.gradient - at.gradient;
    const double ys = y.dot(s);
    if (ys > 1e-12 * s.norm() * y.norm()) {
      if (!qn.scaled) {
        qn.H *= ys / y.squaredNorm();
        qn.scaled = true;
      }
      const double rho = 1.0 / ys;
      const Eigen::MatrixXd E = Eigen::MatrixXd::Identity(n, n) - rho * s * y.transpose();
      qn.H = E * qn.H * E.transpose() + rho * s * s.transpose();
    }
    const double decrease = at.cost_N_s - trial.cost_N_s;
    at = std::move(trial);
    ++steps;
    small = decrease <= relative_tolerance * std::abs(at.cost_N_s) ? small + 1 : 0;
    if (small >= 2) break;
  }
  return steps;
}

// The exchange's time points: uniform at first, then where the plan violates a row on the grid.
struct ExchangePoints {
  const SosSetup& setup;
  const FlatOutputMap& flat;
  const PathParameterization& P;
  std::vector<PathPoint> points;
  std::vector<double> times;

  // per_span points on every span of the flat outputs and of the path: the path's short spans
  // (graded knots) start with points of their own instead of waiting for the exchange.
  ExchangePoints(const SosSetup& s, const FlatOutputMap& f, const PathParameterization& p, int per_span)
      : setup(s), flat(f), P(p) {
    for (const BSplineBasis* basis : {&setup.basis, &P.basis})
      for (double t : basis->pointsPerSpan(per_span)) add(t);
    add(setup.duration_s);
  }
  bool add(double t) {
    for (double s : times)
      if (std::abs(s - t) < 1e-9) return false;
    times.push_back(t);
    points.push_back(make_path_point(setup, flat, P, t));
    return true;
  }
};

enum class GridVerdict { Holds, PointsAdded, Stuck };

// Whether a round's new points changed the cost at the points by so little that more rounds
// would not move the path: the joint Newton method's exchange then ends (the plan along the path
// meets every row). Its rounds are solved to Ipopt's tolerance, so the change is the new points'
// doing; the quasi-Newton method stops its rounds on V's kinks, and a small change there may be
// its own early stop (on the cubic fixture it ended 0.25 % above the joint method).
bool settled(double last_cost, double cost, const FreePathSettings& o) {
  return std::abs(cost - last_cost) <= o.exchange_relative_tolerance * std::abs(cost);
}

// Checks the plan (theta, path of c) on the dense grid, records its worst violations in `out`, and
// adds a point at each local maximum of a violation; `out.failure` says when none is new.
GridVerdict check_and_extend(ExchangePoints& pts, const Eigen::VectorXd& theta, const Eigen::VectorXd& c,
                             const Eigen::VectorXd& reserves, const Eigen::VectorXd& a_min, const FreePathSettings& o,
                             FreePathOutcome& out) {
  const double T = pts.setup.duration_s;
  const GridViolations g = check_grid(pts.setup, pts.flat, pts.P.path(c), theta, reserves, a_min, o.check_points);
  out.worst_bound_excess = g.worst_excess;
  out.min_reserve_margin_N = -g.worst_deficit_N;
  if (g.worst_excess <= o.tolerance && g.worst_deficit_N <= o.tolerance_N) return GridVerdict::Holds;
  std::vector<double> violated;
  local_maxima(g.excess, T, o.tolerance, violated);
  local_maxima(g.deficit_N, T, o.tolerance_N, violated);
  bool added = false;
  for (double t : violated) added |= pts.add(t);
  if (added) return GridVerdict::PointsAdded;
  out.failure = "violations remain at points already imposed";
  return GridVerdict::Stuck;
}

// The joint Newton method: one Ipopt problem over z = (theta, c) per exchange round, each started
// from the last round's optimum.
FreePathOutcome optimize_by_joint_newton(const SosSetup& setup, const FlatOutputMap& flat, const JointPath& start_path,
                                         const Eigen::MatrixXd& initial_q_jet, const Eigen::VectorXd& target,
                                         const Eigen::VectorXd& theta_start, const Eigen::VectorXd& reserves,
                                         const Eigen::VectorXd& a_min, const FreePathSettings& o) {
  const PathParameterization P = parameterize(o, setup.duration_s, initial_q_jet, target);
  const PathVariables v{setup.free_coefficients, P.free};
  FreePathOutcome out;
  ExchangePoints pts(setup, flat, P, o.points_per_span);
  const std::vector<PathPoint>& points = pts.points;
  JointPathNlpPoint at;
  at.z.resize(v.size());
  at.z << theta_start, fit_to(P, start_path);
  std::size_t solved_points = 0;  // of the last round (its multipliers start the next)
  bool solved_once = false;
  double last_cost = 0.0;  // the last round's, at its points
  for (int round = 0; round < o.max_rounds; ++round) {
    out.rounds = round + 1;
    out.points = static_cast<int>(points.size());
    const JointPathNlpOutcome nlp = solve_joint_path_nlp(setup, flat, v, points, reserves, a_min, at, solved_points,
                                                         kNewtonTolerance, o.max_newton_iterations);
    out.path_iterations += nlp.iterations;
    if (!nlp.solved) {
      out.infeasible = !solved_once && nlp.infeasible;
      out.failure = "Ipopt stopped with " + nlp.solver_status + " on " + std::to_string(points.size()) + " points";
      break;
    }
    solved_once = true;
    at = nlp.at;
    solved_points = points.size();
    const double cost = setup.cost_constant + setup.lp.cost.dot(v.theta(at.z));
    if (round > 0 && settled(last_cost, cost, o)) {
      out.converged = true;
      break;
    }
    last_cost = cost;
    const GridVerdict verdict = check_and_extend(pts, v.theta(at.z), v.c(at.z), reserves, a_min, o, out);
    out.converged = verdict == GridVerdict::Holds;
    if (verdict != GridVerdict::PointsAdded) break;
  }
  if (!out.converged && out.failure.empty())
    out.failure = "the joint path's exchange did not converge in " + std::to_string(out.rounds) + " rounds";
  out.theta = v.theta(at.z);
  out.times_s = pts.times;
  out.path = P.path(v.c(at.z));
  out.cost_N_s = setup.cost_constant + setup.lp.cost.dot(out.theta);
  return out;
}

// The reduced-space method: BFGS on V(c) with the envelope gradient, exchange rounds around it.
FreePathOutcome optimize_by_quasi_newton(const SosSetup& setup, const FlatOutputMap& flat, const JointPath& start_path,
                                         const Eigen::MatrixXd& initial_q_jet, const Eigen::VectorXd& target,
                                         const Eigen::VectorXd& theta_start, const Eigen::VectorXd& reserves,
                                         const Eigen::VectorXd& a_min, const FreePathSettings& o) {
  const PathParameterization P = parameterize(o, setup.duration_s, initial_q_jet, target);
  FreePathOutcome out;
  ExchangePoints pts(setup, flat, P, o.points_per_span);
  // A nonlinear effort's integrand is defined where the bounds hold (between bound points a step
  // may ask for a faster deactivation than any excitation gives, and the effort's value and
  // gradient there are the closest excitation's, not smooth): its quadrature points are exchange
  // points from the start. On the paper's arm the quasi-Newton steps then converged (103 steps to
  // 0.098946 s) where they crept without (2024 steps to 0.099016 s).
  std::optional<PathEffort> effort;
  if (o.effort) {
    effort.emplace(setup, flat, P, *o.effort);
    for (double t : effort->times_s()) pts.add(t);
  }
  const std::vector<PathPoint>& points = pts.points;  // V reads them as they grow
  ValueFunction V(setup, flat, points, P, reserves, a_min, o.max_sequential_lp_iterations,
                  effort ? &*effort : nullptr);
  Evaluation start;
  start.theta = theta_start;
  start.radius = 0.1 * (1.0 + theta_start.cwiseAbs().maxCoeff());
  Evaluation at = V(fit_to(P, start_path), start);
  QuasiNewton qn;
  for (int round = 0; round < o.max_rounds; ++round) {
    out.rounds = round + 1;
    out.points = static_cast<int>(points.size());
    if (!at.ok) {
      out.infeasible = round == 0;
      out.failure = "no plan meets the rows at the points" + std::string(round == 0 ? " along the start path" : "") +
                    " (" + at.failure + ")";
      break;
    }
    out.path_iterations += minimize(V, qn, at, o.relative_tolerance, o.max_path_iterations);
    const GridVerdict verdict = check_and_extend(pts, at.theta, at.c, reserves, a_min, o, out);
    out.converged = verdict == GridVerdict::Holds;
    if (verdict != GridVerdict::PointsAdded) break;
    at = V(at.c, at);  // V at the new points (higher: more rows), from the same path and plan
  }
  if (!out.converged && out.failure.empty())
    out.failure = "the joint path's exchange did not converge in " + std::to_string(out.rounds) + " rounds";
  out.evaluations = V.evaluations;
  out.sequential_lp_iterations = V.sequential_lp_iterations;
  if (at.theta.size()) out.theta = at.theta;
  out.times_s = pts.times;
  if (at.c.size()) out.path = P.path(at.c);
  out.cost_N_s = at.cost_N_s;
  return out;
}

}  // namespace

FreePathOutcome optimize_joint_path(const SosSetup& setup, const FlatOutputMap& flat, const JointPath& start_path,
                                    const Eigen::MatrixXd& initial_q_jet, const Eigen::VectorXd& target,
                                    const Eigen::VectorXd& theta_start, const Eigen::VectorXd& reserves,
                                    const Eigen::VectorXd& a_min, const FreePathSettings& o) {
  if (o.effort && o.method == FreePathMethod::JointNewton)
    throw std::invalid_argument("free path: the joint Newton method minimizes the map's linear effort; the effort '" +
                                o.effort->name() + "' takes the reduced quasi-Newton method");
  return o.method == FreePathMethod::JointNewton
             ? optimize_by_joint_newton(setup, flat, start_path, initial_q_jet, target, theta_start, reserves, a_min, o)
             : optimize_by_quasi_newton(setup, flat, start_path, initial_q_jet, target, theta_start, reserves, a_min, o);
}

Eigen::VectorXd path_coefficients(const SosSetup& setup, const JointPath& path, const Eigen::MatrixXd& initial_q_jet,
                                  const Eigen::VectorXd& target, const FreePathSettings& o) {
  return fit_to(parameterize(o, setup.duration_s, initial_q_jet, target), path);
}

JointPath path_of(const SosSetup& setup, const Eigen::VectorXd& c, const Eigen::MatrixXd& initial_q_jet,
                  const Eigen::VectorXd& target, const FreePathSettings& o) {
  return parameterize(o, setup.duration_s, initial_q_jet, target).path(c);
}

PathValue path_value(const SosSetup& setup, const FlatOutputMap& flat, const Eigen::MatrixXd& initial_q_jet,
                     const Eigen::VectorXd& target, const Eigen::VectorXd& reserves, const Eigen::VectorXd& a_min,
                     const FreePathSettings& o, const std::vector<double>& times, const Eigen::VectorXd& c,
                     const Eigen::VectorXd& theta_start) {
  const PathParameterization P = parameterize(o, setup.duration_s, initial_q_jet, target);
  if (c.size() != P.free) throw std::invalid_argument("path value: c has " + std::to_string(c.size()) + " entries, the path " + std::to_string(P.free));
  std::vector<PathPoint> points;
  for (double t : times) points.push_back(make_path_point(setup, flat, P, t));
  std::optional<PathEffort> effort;
  if (o.effort) effort.emplace(setup, flat, P, *o.effort);
  ValueFunction V(setup, flat, points, P, reserves, a_min, o.max_sequential_lp_iterations,
                  effort ? &*effort : nullptr);
  Evaluation start;
  start.theta = theta_start;
  start.radius = 0.1 * (1.0 + theta_start.cwiseAbs().maxCoeff());
  const Evaluation e = V(c, start);
  return {e.ok, e.failure, e.cost_N_s, e.theta, e.gradient, e.active_reserve_rows, e.active_bound_rows};
}

}  // namespace flatsos::planner::detail
