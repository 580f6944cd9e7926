#include "path/free_path.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>

#include "bounds/bound_rows.hpp"
#include "bounds/sequential_lp.hpp"
#include "path/joint_path_nlp.hpp"
#include "path/path_rows.hpp"

namespace flatsos::planner::detail {

namespace {

constexpr double kFirstStep_rad = 0.05;       // the first quasi-Newton step's largest coefficient change
constexpr double kArmijo = 1e-4;
constexpr int kMaxBacktracks = 12;
constexpr double kRoundStartRadius = 0.01;  // the SLP's trust radius after new points, of the largest coefficient
// Ipopt's (scaled) optimality tolerance per round. The path stage only has to find the path: the
// plan along it is solved and certified anew, so the barrier's last decades bought nothing there
// (1e-8: 156 iterations on the arm, 1e-6: 86, at 186.5849 against 186.5847 N s; later 1e-6: 558
// iterations over seven configurations, 1e-5: 529, every certified plan the same to 1e-6,
// docs/method/free_path.md).
constexpr double kNewtonTolerance = 1e-5;

// For a fixed path c, the plan's rows at the points over theta alone: the bound rows (nonlinear)
// and the linear rows, group-major as the SLP's basis keys them: a group per muscle (F_j >=
// reserve_j), then a group per flat output (Y_l >= 0), a row per point in each.
struct RowsAlongPath {
  std::vector<BoundPoint> bound_points;
  LinearProgram lp;
  std::vector<std::size_t> rows_per_group;
};

RowsAlongPath rows_along_path(const SosSetup& setup, const FlatOutputMap& flat, const std::vector<PathPoint>& points,
                              const Eigen::VectorXd& c, const Eigen::VectorXd& reserves) {
  const int m = flat.numMuscles(), p = flat.numFlatOutputs();
  const auto count = static_cast<Eigen::Index>(points.size());
  RowsAlongPath out;
  out.bound_points.reserve(points.size());
  for (const PathPoint& pt : points) {
    const Eigen::MatrixXd q = joint_jet(pt, c);
    BoundPoint bp = pt.flat;
    bp.base += flat.Ctau() * flat.model().pinTree().torqueJet(q);
    bp.path.resize(static_cast<std::size_t>(m));
    for (int j = 0; j < m; ++j) bp.path[static_cast<std::size_t>(j)] = flat.pathLengthJet(j, q);
    out.bound_points.push_back(std::move(bp));
  }
  LinearProgram& lp = out.lp;
  lp.cost = setup.lp.cost;
  lp.x_lower = setup.lp.x_lower;
  lp.x_upper = setup.lp.x_upper;
  lp.G = Eigen::MatrixXd::Zero(count * (m + p), setup.free_coefficients);
  lp.row_lower.resize(lp.G.rows());
  lp.row_upper = Eigen::VectorXd::Constant(lp.G.rows(), 1e19);
  for (int j = 0; j < m; ++j)
    for (Eigen::Index k = 0; k < count; ++k) {
      const BoundPoint& bp = out.bound_points[static_cast<std::size_t>(k)];
      const Eigen::Index row = j * count + k;
      for (std::size_t col = 0; col < bp.columns.size(); ++col) lp.G(row, bp.columns[col]) = bp.slope[0](j, static_cast<Eigen::Index>(col));
      lp.row_lower[row] = reserves[j] + kReserveMargin_N - bp.base(j, 0);
    }
  for (int l = 0; l < p; ++l) {
    const OutputParameterization& y = setup.outputs[static_cast<std::size_t>(l)];
    for (Eigen::Index k = 0; k < count; ++k) {
      const Eigen::RowVectorXd b = setup.basis.derivativeRow(points[static_cast<std::size_t>(k)].flat.t_s, 0);
      const Eigen::Index row = (m + l) * count + k;
      if (y.nullspace.cols()) lp.G.block(row, y.offset, 1, y.nullspace.cols()) = b * y.nullspace;
      lp.row_lower[row] = -b.dot(y.particular);
    }
  }
  out.rows_per_group.assign(static_cast<std::size_t>(m + p), static_cast<std::size_t>(count));
  return out;
}

// V(c), theta there and dV/dc, and the SLP's state to start the next evaluation from.
struct Evaluation {
  bool ok = false;
  std::string failure;
  double cost_N_s = std::numeric_limits<double>::infinity();
  Eigen::VectorXd c, theta, gradient;
  SequentialLpBasis basis;
  double radius = 0.0;
  int sequential_lp_iterations = 0;
  int active_reserve_rows = 0, active_bound_rows = 0;
};

class ValueFunction {
 public:
  ValueFunction(const SosSetup& setup, const FlatOutputMap& flat, const std::vector<PathPoint>& points, int path_coefficients,
                const Eigen::VectorXd& reserves, const Eigen::VectorXd& a_min, int max_sequential_lp_iterations)
      : setup_(setup), flat_(flat), points_(points), reserves_(reserves), a_min_(a_min), max_slp_(max_sequential_lp_iterations) {
    v_.thetas = setup.free_coefficients;
    v_.paths = path_coefficients;
  }

  int evaluations = 0, sequential_lp_iterations = 0;

  // Starts the plan's SLP from `from` (theta, basis, radius).
  Evaluation operator()(const Eigen::VectorXd& c, const Evaluation& from) {
    ++evaluations;
    Evaluation e;
    e.c = c;
    e.theta = from.theta;
    e.basis = from.basis;
    // A new path moves the rows by up to newtons: a radius as small as the last converged step
    // would take many doublings to grow back (as after the exchange's new points).
    e.radius = std::max(from.radius, kRoundStartRadius * (1.0 + e.theta.cwiseAbs().maxCoeff()));
    const RowsAlongPath rows = rows_along_path(setup_, flat_, points_, c, reserves_);
    const SequentialLpLinearPart linear{rows.lp, rows.rows_per_group, kReserveMargin_N};
    // Every candidate row in each step LP (no working set): the path's quasi-Newton steps follow
    // the multipliers of degenerate step LPs, and with the working set's other optimal vertices
    // they stopped 0.1 % higher on the arm (281.4 against 281.1 N s, at a point a random move
    // of 0.01 rad still lowers by 1.3e-4).
    SequentialLpSettings settings;
    settings.max_iterations = max_slp_;
    settings.working_set = false;
    const SequentialLpOutcome slp = solve_by_sequential_lp(linear, bound_rows_of(flat_, rows.bound_points, a_min_, kBoundMargin), e.theta,
                                               e.radius, e.basis, settings);
    e.sequential_lp_iterations = slp.iterations;
    sequential_lp_iterations += slp.iterations;
    if (!slp.converged || slp.rows_violated) {
      e.failure = slp.rows_violated ? "the rows cannot be met at every point" : slp.failure;
      return e;
    }
    e.ok = true;
    e.cost_N_s = setup_.cost_constant + setup_.lp.cost.dot(e.theta);
    e.gradient = gradient(c, e.theta, slp, points_.size());
    for (double l : slp.row_multipliers) e.active_bound_rows += l > 0.0;
    for (Eigen::Index r = 0; r < slp.linear_row_multipliers.size(); ++r) e.active_reserve_rows += slp.linear_row_multipliers[r] > 0.0;
    return e;
  }

 private:
  // dV/dc = -sum_k lambda_k d g_k / d c over the rows that depend on c (reserves and bounds), at
  // the points where some multiplier is not zero.
  Eigen::VectorXd gradient(const Eigen::VectorXd& c, const Eigen::VectorXd& theta, const SequentialLpOutcome& slp,
                           std::size_t count) const {
    const int m = flat_.numMuscles();
    constexpr int kRows = PathRows::kRows;
    std::vector<double> lambda(count * static_cast<std::size_t>(m * kRows), 0.0);  // PathRows' layout
    for (std::size_t i = 0; i < slp.row_multipliers.size(); ++i) {
      const std::size_t point_muscle = i / kRowsPerMuscle, k = i % kRowsPerMuscle;
      lambda[point_muscle * kRows + 1 + k] = slp.row_multipliers[i];
    }
    for (int j = 0; j < m; ++j)
      for (std::size_t k = 0; k < count; ++k)
        lambda[(k * static_cast<std::size_t>(m) + static_cast<std::size_t>(j)) * kRows] =
            slp.linear_row_multipliers[static_cast<Eigen::Index>(static_cast<std::size_t>(j) * count + k)];
    std::vector<PathPoint> active;
    std::vector<double> active_lambda;
    for (std::size_t k = 0; k < count; ++k) {
      const auto first = lambda.begin() + static_cast<std::ptrdiff_t>(k * static_cast<std::size_t>(m * kRows));
      if (std::all_of(first, first + m * kRows, [](double l) { return l == 0.0; })) continue;
      active.push_back(points_[k]);
      active_lambda.insert(active_lambda.end(), first, first + m * kRows);
    }
    Eigen::VectorXd z(v_.thetas + v_.paths);
    z << theta, c;
    const BoundRowsAt rows = PathRows(flat_, v_, active, reserves_, a_min_)(z, true);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(v_.paths);
    for (const auto& t : rows.jacobian)
      if (t.col() >= v_.thetas) g[t.col() - v_.thetas] -= active_lambda[static_cast<std::size_t>(t.row())] * t.value();
    return g;
  }

  const SosSetup& setup_;
  const FlatOutputMap& flat_;
  const std::vector<PathPoint>& points_;
  const Eigen::VectorXd& reserves_;
  const Eigen::VectorXd& a_min_;
  const int max_slp_;
  PathVariables v_;
};

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
  const std::vector<PathPoint>& points = pts.points;  // V reads them as they grow
  ValueFunction V(setup, flat, points, P.free, reserves, a_min, o.max_sequential_lp_iterations);
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
  ValueFunction V(setup, flat, points, P.free, reserves, a_min, o.max_sequential_lp_iterations);
  Evaluation start;
  start.theta = theta_start;
  start.radius = 0.1 * (1.0 + theta_start.cwiseAbs().maxCoeff());
  const Evaluation e = V(c, start);
  return {e.ok, e.failure, e.cost_N_s, e.theta, e.gradient, e.active_reserve_rows, e.active_bound_rows};
}

}  // namespace flatsos::planner::detail
