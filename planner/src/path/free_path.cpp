#include "path/free_path.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>

#include "sos/bound_rows.hpp"
#include "sos/bounds_slp.hpp"

namespace flatsos::planner::detail {

namespace {

constexpr int kOrders = 5;                   // q .. q'''' (the excitation needs d2 tau / dt2)
constexpr double kReserveMargin_N = 1e-6;    // reserve rows hold F >= reserve + this
constexpr double kFirstStep_rad = 0.05;       // the first quasi-Newton step's largest coefficient change
constexpr double kArmijo = 1e-4;
constexpr int kMaxBacktracks = 12;
constexpr double kRoundStartRadius = 0.01;  // the SLP's trust radius after new points, of the largest coefficient

// The joint path's spline: q_i = B (particular_i + nullspace_i c_i), c = [c_0; c_1; ...].
struct PathParameterization {
  explicit PathParameterization(BSplineBasis b) : basis(std::move(b)) {}
  BSplineBasis basis;
  std::vector<OutputParameterization> joints;
  int free = 0;

  Eigen::MatrixXd coefficients(const Eigen::VectorXd& c) const {
    Eigen::MatrixXd out(static_cast<Eigen::Index>(joints.size()), basis.size());
    for (std::size_t i = 0; i < joints.size(); ++i) {
      const auto& j = joints[i];
      Eigen::VectorXd row = j.particular;
      if (j.nullspace.cols()) row += j.nullspace * c.segment(j.offset, j.nullspace.cols());
      out.row(static_cast<Eigen::Index>(i)) = row.transpose();
    }
    return out;
  }
  JointPath path(const Eigen::VectorXd& c) const { return JointPath::fromSpline(SplineTrajectory(basis, coefficients(c))); }
};

PathParameterization parameterize(const FreeJointPathOptions& o, double T, const Eigen::MatrixXd& initial,
                                  const Eigen::VectorXd& target) {
  PathParameterization out(BSplineBasis(o.degree, o.spans, T));
  FlatOutputBoundary bc;
  bc.initial = initial;
  bc.terminal = Eigen::MatrixXd::Zero(target.size(), kOrders);
  bc.terminal.col(0) = target;
  bc.terminal_first_order = 0;
  for (Eigen::Index i = 0; i < target.size(); ++i) {
    OutputParameterization j = eliminate_equalities(out.basis, bc, static_cast<int>(i));
    j.offset = out.free;
    out.free += static_cast<int>(j.nullspace.cols());
    out.joints.push_back(std::move(j));
  }
  return out;
}

// The c whose spline is closest (least squares on a fine grid) to `path`: exact when the
// spline's space holds it (degree 8: the prescribed path itself).
Eigen::VectorXd fit_to(const PathParameterization& P, const JointPath& path) {
  const int samples = 8 * P.basis.spans() * (P.basis.degree() + 1) + 1;
  Eigen::VectorXd c = Eigen::VectorXd::Zero(P.free);
  for (std::size_t i = 0; i < P.joints.size(); ++i) {
    const auto& j = P.joints[i];
    if (!j.nullspace.cols()) continue;
    Eigen::MatrixXd A(samples, j.nullspace.cols());
    Eigen::VectorXd b(samples);
    for (int k = 0; k < samples; ++k) {
      const double t = P.basis.duration() * k / (samples - 1);
      const Eigen::RowVectorXd row = P.basis.derivativeRow(t, 0);
      A.row(k) = row * j.nullspace;
      b[k] = path.jet(t, 1)(static_cast<Eigen::Index>(i), 0) - row.dot(j.particular);
    }
    c.segment(j.offset, j.nullspace.cols()) = A.colPivHouseholderQr().solve(b);
  }
  return c;
}

// Everything about one time point that does not depend on the variables.
struct PathPoint {
  BoundPoint flat;                        // F's flat-output part: base + slope theta
  Eigen::MatrixXd q_base;                 // N x 5: the joint jet at c = 0
  std::array<Eigen::MatrixXd, kOrders> q_slope;  // per order: N x free (d q^(l) / d c)
};

PathPoint make_path_point(const SosSetup& setup, const FlatOutputMap& flat, const PathParameterization& P, double t) {
  PathPoint pt{flat_output_point(setup, flat, t), Eigen::MatrixXd(flat.numJoints(), kOrders), {}};
  for (int l = 0; l < kOrders; ++l) {
    const Eigen::RowVectorXd row = P.basis.derivativeRow(t, l);
    auto& slope = pt.q_slope[static_cast<std::size_t>(l)];
    slope = Eigen::MatrixXd::Zero(flat.numJoints(), P.free);
    for (std::size_t i = 0; i < P.joints.size(); ++i) {
      const auto& j = P.joints[i];
      pt.q_base(static_cast<Eigen::Index>(i), l) = row.dot(j.particular);
      if (j.nullspace.cols()) slope.block(static_cast<Eigen::Index>(i), j.offset, 1, j.nullspace.cols()) = row * j.nullspace;
    }
  }
  return pt;
}

// The rows' variables z = (theta, c).
struct Variables {
  int thetas = 0, paths = 0;
  Eigen::VectorXd theta(const Eigen::VectorXd& z) const { return z.head(thetas); }
  Eigen::VectorXd c(const Eigen::VectorXd& z) const { return z.tail(paths); }
};

class PathRows {
 public:
  PathRows(const FlatOutputMap& flat, const Variables& v, const std::vector<PathPoint>& points, const Eigen::VectorXd& reserves,
           const Eigen::VectorXd& a_min)
      : flat_(flat), v_(v), points_(points), reserves_(reserves), a_min_(a_min) {}

  // Per point and muscle: the reserve row, then the four bound rows.
  static constexpr int kRows = 1 + kRowsPerMuscle;

  BoundRowsAt operator()(const Eigen::VectorXd& z, bool jacobian) const {
    const int n = flat_.numJoints(), m = flat_.numMuscles();
    const Eigen::VectorXd theta = v_.theta(z), c = v_.c(z);
    BoundRowsAt out;
    out.value.reserve(points_.size() * static_cast<std::size_t>(m * kRows));
    Eigen::MatrixXd q_jet(n, kOrders), tau_gradient, dq(kOrders * n, v_.paths), path_gradient(3, kOrders * n);
    int row = 0;
    for (const PathPoint& pt : points_) {
      q_jet = pt.q_base;
      for (int l = 0; l < kOrders; ++l) q_jet.col(l) += pt.q_slope[static_cast<std::size_t>(l)] * c;
      const Eigen::MatrixXd tau = jacobian ? flat_.model().pinTree().torqueJet(q_jet, tau_gradient)
                                           : flat_.model().pinTree().torqueJet(q_jet);
      // F^(k) = base + slope theta + C_tau tau^(k).
      Eigen::MatrixXd F = pt.flat.base + flat_.Ctau() * tau;
      for (int k = 0; k < 3; ++k)
        for (std::size_t col = 0; col < pt.flat.columns.size(); ++col)
          F.col(k) += pt.flat.slope[static_cast<std::size_t>(k)].col(static_cast<Eigen::Index>(col)) * theta[pt.flat.columns[col]];
      std::array<Eigen::MatrixXd, 3> dF_dc;  // m x paths (per unit z)
      if (jacobian) {
        for (int r = 0; r < n; ++r)
          for (int l = 0; l < kOrders; ++l) dq.row(kOrders * r + l) = pt.q_slope[static_cast<std::size_t>(l)].row(r);
        const Eigen::MatrixXd dtau = tau_gradient * dq;  // 3N x paths, row 3 i + k
        for (int k = 0; k < 3; ++k) {
          Eigen::MatrixXd dtau_k(n, v_.paths);
          for (int i = 0; i < n; ++i) dtau_k.row(i) = dtau.row(3 * i + k);
          dF_dc[static_cast<std::size_t>(k)] = flat_.Ctau() * dtau_k;
        }
      }
      for (int j = 0; j < m; ++j) {
        const muscles::SecondOrderJet path = flat_.pathLengthJet(j, q_jet);
        const MuscleBoundRows bounds = muscle_bound_rows(flat_.model().muscle(j).getParameters(), {F(j, 0), F(j, 1), F(j, 2)},
                                                         path, a_min_[j], jacobian);
        const double reserve_value = F(j, 0) - reserves_[j] - kReserveMargin_N;
        out.value.push_back(reserve_value);
        out.violation += std::max(0.0, -reserve_value);
        for (int k = 0; k < kRowsPerMuscle; ++k) {
          const double v = bounds.value[static_cast<std::size_t>(k)];
          out.value.push_back(v);
          out.violation += std::max(0.0, -v);
        }
        if (jacobian) {
          // The reserve row: dF / d(theta, c).
          for (std::size_t col = 0; col < pt.flat.columns.size(); ++col)
            out.jacobian.emplace_back(row, pt.flat.columns[col], pt.flat.slope[0](j, static_cast<Eigen::Index>(col)));
          for (int col = 0; col < v_.paths; ++col) out.jacobian.emplace_back(row, v_.thetas + col, dF_dc[0](j, col));
          flat_.pathLengthJetGradient(j, q_jet, path_gradient);
          const Eigen::MatrixXd dL = path_gradient * dq;  // 3 x paths
          for (int k = 0; k < kRowsPerMuscle; ++k) {
            const auto& g = bounds.gradient[static_cast<std::size_t>(k)];
            const auto& pg = bounds.path_gradient[static_cast<std::size_t>(k)];
            for (std::size_t col = 0; col < pt.flat.columns.size(); ++col)
              out.jacobian.emplace_back(row + 1 + k, pt.flat.columns[col], column_derivative(pt.flat, g, j, col));
            for (int col = 0; col < v_.paths; ++col) {
              double d = 0.0;
              for (std::size_t o = 0; o < 3; ++o)
                d += g[o] * dF_dc[o](j, col) + pg[o] * dL(static_cast<Eigen::Index>(o), col);
              out.jacobian.emplace_back(row + 1 + k, v_.thetas + col, d);
            }
          }
        }
        row += kRows;
      }
    }
    return out;
  }

 private:
  const FlatOutputMap& flat_;
  const Variables& v_;
  const std::vector<PathPoint>& points_;
  const Eigen::VectorXd& reserves_;
  const Eigen::VectorXd& a_min_;
};

// The plan on a dense grid: per time the reserve deficit (N) and the bounds' excess, and their worst.
struct GridViolations {
  std::vector<double> deficit_N, excess;
  double worst_deficit_N = 0.0, worst_excess = 0.0;
};

GridViolations check_grid(const SosSetup& setup, const FlatOutputMap& flat, const JointPath& path,
                          const Eigen::VectorXd& theta, const Eigen::VectorXd& reserves, const Eigen::VectorXd& a_min,
                          int points) {
  const SplineTrajectory Y = flat_outputs_of(setup, theta);
  GridViolations g;
  g.deficit_N.assign(static_cast<std::size_t>(points), 0.0);
  g.excess.assign(static_cast<std::size_t>(points), 0.0);
  Jet q_jet(flat.numJoints(), kOrders), y_jet(flat.numFlatOutputs(), 3);
  for (int i = 0; i < points; ++i) {
    const double t = path.duration_s * i / (points - 1);
    path.jetInto(t, q_jet);
    Y.jetInto(t, y_jet);
    const Eigen::MatrixXd F = flat.Ctau() * flat.model().pinTree().torqueJet(q_jet) + flat.CY() * y_jet;
    for (int j = 0; j < flat.numMuscles(); ++j) {
      const auto& p = flat.model().muscle(j).getParameters();
      const muscles::MuscleInverse inv = muscles::invert_muscle(p, {F(j, 0), F(j, 1), F(j, 2)}, flat.pathLengthJet(j, q_jet), false);
      double e = std::numeric_limits<double>::infinity();
      if (inv.stage == muscles::MuscleInverse::Stage::Complete && inv.excitation_real && std::isfinite(inv.excitation))
        e = std::max({a_min[j] - inv.activation, inv.activation - 1.0, -inv.excitation, inv.excitation - 1.0, 0.0});
      const auto k = static_cast<std::size_t>(i);
      g.excess[k] = std::max(g.excess[k], e);
      g.deficit_N[k] = std::max(g.deficit_N[k], reserves[j] - F(j, 0));
    }
    g.worst_excess = std::max(g.worst_excess, g.excess[static_cast<std::size_t>(i)]);
    g.worst_deficit_N = std::max(g.worst_deficit_N, g.deficit_N[static_cast<std::size_t>(i)]);
  }
  return g;
}

// Times where a violation is a local maximum above `tolerance`.
void local_maxima(const std::vector<double>& v, double T, double tolerance, std::vector<double>& times) {
  const std::size_t n = v.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (!(v[i] > tolerance)) continue;
    if ((i == 0 || v[i] >= v[i - 1]) && (i + 1 == n || v[i] >= v[i + 1])) times.push_back(T * static_cast<double>(i) / static_cast<double>(n - 1));
  }
}

// The joint jet of the path of c at a point.
Eigen::MatrixXd joint_jet(const PathPoint& pt, const Eigen::VectorXd& c) {
  Eigen::MatrixXd q = pt.q_base;
  for (int l = 0; l < kOrders; ++l) q.col(l) += pt.q_slope[static_cast<std::size_t>(l)] * c;
  return q;
}

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
  SlpBasis basis;
  double radius = 0.0;
  int slp_iterations = 0;
  int active_reserve_rows = 0, active_bound_rows = 0;
};

class ValueFunction {
 public:
  ValueFunction(const SosSetup& setup, const FlatOutputMap& flat, const std::vector<PathPoint>& points, int path_coefficients,
                const Eigen::VectorXd& reserves, const Eigen::VectorXd& a_min, int max_slp_iterations)
      : setup_(setup), flat_(flat), points_(points), reserves_(reserves), a_min_(a_min), max_slp_(max_slp_iterations) {
    v_.thetas = setup.free_coefficients;
    v_.paths = path_coefficients;
  }

  int evaluations = 0, slp_iterations = 0;

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
    const SlpLinearPart linear{rows.lp, rows.rows_per_group, kReserveMargin_N};
    // Every candidate row in each step LP (no working set): the path's quasi-Newton steps follow
    // the multipliers of degenerate step LPs, and with the working set's other optimal vertices
    // they stopped 0.1 % higher on the arm (281.4 against 281.1 N s, at a point a random move
    // of 0.01 rad still lowers by 1.3e-4).
    SlpSettings settings;
    settings.max_iterations = max_slp_;
    settings.working_set = false;
    const SlpOutcome slp = solve_bounds_by_slp(linear, bound_rows_of(flat_, rows.bound_points, a_min_, kBoundMargin), e.theta,
                                               e.radius, e.basis, settings);
    e.slp_iterations = slp.iterations;
    slp_iterations += slp.iterations;
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
  Eigen::VectorXd gradient(const Eigen::VectorXd& c, const Eigen::VectorXd& theta, const SlpOutcome& slp,
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
  Variables v_;
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

}  // namespace

FreePathOutcome optimize_joint_path(const SosSetup& setup, const FlatOutputMap& flat, const JointPath& start_path,
                                    const Eigen::MatrixXd& initial_q_jet, const Eigen::VectorXd& target,
                                    const Eigen::VectorXd& theta_start, const Eigen::VectorXd& reserves,
                                    const Eigen::VectorXd& a_min, const FreeJointPathOptions& o) {
  const double T = setup.duration_s;
  const PathParameterization P = parameterize(o, T, initial_q_jet, target);
  FreePathOutcome out;
  std::vector<PathPoint> points;
  std::vector<double> times;
  auto add_point = [&](double t) {
    for (double s : times)
      if (std::abs(s - t) < 1e-9) return false;
    times.push_back(t);
    points.push_back(make_path_point(setup, flat, P, t));
    return true;
  };
  const int uniform = o.points_per_span * setup.basis.spans();
  for (int i = 0; i <= uniform; ++i) add_point(T * i / uniform);

  ValueFunction V(setup, flat, points, P.free, reserves, a_min, o.max_slp_iterations);
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
    const GridViolations g = check_grid(setup, flat, P.path(at.c), at.theta, reserves, a_min, o.check_points);
    out.worst_bound_excess = g.worst_excess;
    out.min_reserve_margin_N = -g.worst_deficit_N;
    if (g.worst_excess <= o.tolerance && g.worst_deficit_N <= o.tolerance_N) {
      out.converged = true;
      break;
    }
    std::vector<double> violated;
    local_maxima(g.excess, T, o.tolerance, violated);
    local_maxima(g.deficit_N, T, o.tolerance_N, violated);
    bool added = false;
    for (double t : violated) added |= add_point(t);
    if (!added) {
      out.failure = "violations remain at points already imposed";
      break;
    }
    at = V(at.c, at);  // V at the new points (higher: more rows), from the same path and plan
  }
  if (!out.converged && out.failure.empty())
    out.failure = "the joint path's exchange did not converge in " + std::to_string(out.rounds) + " rounds";
  out.evaluations = V.evaluations;
  out.slp_iterations = V.slp_iterations;
  if (at.theta.size()) out.theta = at.theta;
  if (at.c.size()) out.path = P.path(at.c);
  out.cost_N_s = at.cost_N_s;
  return out;
}

Eigen::VectorXd path_coefficients(const SosSetup& setup, const JointPath& path, const Eigen::MatrixXd& initial_q_jet,
                                  const Eigen::VectorXd& target, const FreeJointPathOptions& o) {
  return fit_to(parameterize(o, setup.duration_s, initial_q_jet, target), path);
}

JointPath path_of(const SosSetup& setup, const Eigen::VectorXd& c, const Eigen::MatrixXd& initial_q_jet,
                  const Eigen::VectorXd& target, const FreeJointPathOptions& o) {
  return parameterize(o, setup.duration_s, initial_q_jet, target).path(c);
}

PathValue path_value(const SosSetup& setup, const FlatOutputMap& flat, const Eigen::MatrixXd& initial_q_jet,
                     const Eigen::VectorXd& target, const Eigen::VectorXd& reserves, const Eigen::VectorXd& a_min,
                     const FreeJointPathOptions& o, const std::vector<double>& times, const Eigen::VectorXd& c,
                     const Eigen::VectorXd& theta_start) {
  const PathParameterization P = parameterize(o, setup.duration_s, initial_q_jet, target);
  if (c.size() != P.free) throw std::invalid_argument("path value: c has " + std::to_string(c.size()) + " entries, the path " + std::to_string(P.free));
  std::vector<PathPoint> points;
  for (double t : times) points.push_back(make_path_point(setup, flat, P, t));
  ValueFunction V(setup, flat, points, P.free, reserves, a_min, o.max_slp_iterations);
  Evaluation start;
  start.theta = theta_start;
  start.radius = 0.1 * (1.0 + theta_start.cwiseAbs().maxCoeff());
  const Evaluation e = V(c, start);
  return {e.ok, e.failure, e.cost_N_s, e.theta, e.gradient, e.active_reserve_rows, e.active_bound_rows};
}

}  // namespace flatsos::planner::detail
