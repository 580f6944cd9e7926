#include "path/path_rows.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Dense>

namespace flatsos::planner::detail {

namespace {
constexpr int kOrders = kPathOrders;

// d (joint jet) / d (the point's path columns): 5N x columns, row kOrders r + l for d^l q_r / dt^l,
// into the left columns of `dq` (at least 5N rows and as many columns as the point has).
void joint_jet_slope_into(const PathPoint& pt, int joints, Eigen::MatrixXd& dq) {
  const auto columns = static_cast<Eigen::Index>(pt.path_columns.size());
  for (int r = 0; r < joints; ++r)
    for (int l = 0; l < kOrders; ++l)
      dq.row(kOrders * r + l).head(columns) = pt.q_slope[static_cast<std::size_t>(l)].row(r);
}

// The tendon-force jets at a point, m x 3: F^(k) = base + slope theta + C_tau tau^(k).
Eigen::MatrixXd force_jet(const PathPoint& pt, const Eigen::MatrixXd& Ctau, const Eigen::MatrixXd& tau,
                          const Eigen::VectorXd& theta) {
  Eigen::MatrixXd F = pt.flat.base + Ctau * tau;
  for (int k = 0; k < 3; ++k)
    for (std::size_t col = 0; col < pt.flat.columns.size(); ++col)
      F.col(k) += pt.flat.slope[static_cast<std::size_t>(k)].col(static_cast<Eigen::Index>(col)) * theta[pt.flat.columns[col]];
  return F;
}
}  // namespace

Eigen::MatrixXd PathParameterization::coefficients(const Eigen::VectorXd& c) const {
  Eigen::MatrixXd out(static_cast<Eigen::Index>(joints.size()), basis.size());
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const auto& j = joints[i];
    Eigen::VectorXd row = j.particular;
    if (j.nullspace.cols()) row += j.nullspace * c.segment(j.offset, j.nullspace.cols());
    out.row(static_cast<Eigen::Index>(i)) = row.transpose();
  }
  return out;
}

JointPath PathParameterization::path(const Eigen::VectorXd& c) const {
  return JointPath::fromSpline(SplineTrajectory(basis, coefficients(c)));
}

PathParameterization parameterize(const FreePathSettings& o, double T, const Eigen::MatrixXd& initial,
                                  const Eigen::VectorXd& target) {
  PathParameterization out(BSplineBasis::geometric(o.degree, o.spans, T, o.span_growth));
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

PathPoint make_path_point(const SosSetup& setup, const FlatOutputMap& flat, const PathParameterization& P, double t) {
  PathPoint pt{flat_output_point(setup, flat, t), Eigen::MatrixXd(flat.numJoints(), kOrders), {}, {}};
  std::array<Eigen::MatrixXd, kOrders> slope;  // per order: N x free
  for (int l = 0; l < kOrders; ++l) {
    const Eigen::RowVectorXd row = P.basis.derivativeRow(t, l);
    auto& s = slope[static_cast<std::size_t>(l)];
    s = Eigen::MatrixXd::Zero(flat.numJoints(), P.free);
    for (std::size_t i = 0; i < P.joints.size(); ++i) {
      const auto& j = P.joints[i];
      pt.q_base(static_cast<Eigen::Index>(i), l) = row.dot(j.particular);
      if (j.nullspace.cols()) s.block(static_cast<Eigen::Index>(i), j.offset, 1, j.nullspace.cols()) = row * j.nullspace;
    }
  }
  // Structural support: the columns any order of any joint touches (exact zeros off the B-splines'
  // support, and off the few end coefficients the boundary equalities couple).
  for (int col = 0; col < P.free; ++col) {
    bool touched = false;
    for (const auto& s : slope) touched = touched || (s.col(col).array() != 0.0).any();
    if (touched) pt.path_columns.push_back(col);
  }
  for (int l = 0; l < kOrders; ++l) {
    auto& local = pt.q_slope[static_cast<std::size_t>(l)];
    local.resize(flat.numJoints(), static_cast<Eigen::Index>(pt.path_columns.size()));
    for (std::size_t k = 0; k < pt.path_columns.size(); ++k)
      local.col(static_cast<Eigen::Index>(k)) = slope[static_cast<std::size_t>(l)].col(pt.path_columns[k]);
  }
  return pt;
}

Eigen::VectorXd PathPoint::localPath(const Eigen::VectorXd& c) const {
  Eigen::VectorXd out(static_cast<Eigen::Index>(path_columns.size()));
  for (std::size_t k = 0; k < path_columns.size(); ++k) out[static_cast<Eigen::Index>(k)] = c[path_columns[k]];
  return out;
}

Eigen::MatrixXd joint_jet_slope(const PathPoint& pt, int joints) {
  Eigen::MatrixXd dq(kOrders * joints, static_cast<Eigen::Index>(pt.path_columns.size()));
  joint_jet_slope_into(pt, joints, dq);
  return dq;
}

Eigen::MatrixXd joint_jet(const PathPoint& pt, const Eigen::VectorXd& c) {
  Eigen::MatrixXd q = pt.q_base;
  const Eigen::VectorXd local = pt.localPath(c);
  for (int l = 0; l < kOrders; ++l) q.col(l) += pt.q_slope[static_cast<std::size_t>(l)] * local;
  return q;
}

std::vector<BoundPoint> bound_points_along_path(const FlatOutputMap& flat, const std::vector<PathPoint>& points,
                                                const Eigen::VectorXd& c) {
  const int m = flat.numMuscles();
  std::vector<BoundPoint> out;
  out.reserve(points.size());
  for (const PathPoint& pt : points) {
    const Eigen::MatrixXd q = joint_jet(pt, c);
    BoundPoint bp = pt.flat;
    bp.base += flat.Ctau() * flat.model().pinTree().torqueJet(q);
    bp.path.resize(static_cast<std::size_t>(m));
    for (int j = 0; j < m; ++j) bp.path[static_cast<std::size_t>(j)] = flat.pathLengthJet(j, q);
    out.push_back(std::move(bp));
  }
  return out;
}

PathRows::PathRows(const FlatOutputMap& flat, const PathVariables& v, const std::vector<PathPoint>& points,
                   const Eigen::VectorXd& reserves, const Eigen::VectorXd& a_min, TorqueCurvature curvature,
                   double inverse_curvature_floor)
    : flat_(flat),
      v_(v),
      points_(points),
      reserves_(reserves),
      a_min_(a_min),
      curvature_(curvature),
      inverse_curvature_floor_(inverse_curvature_floor) {
  if (!(inverse_curvature_floor >= 0.0))
    throw std::invalid_argument("free path rows: the inverse's curvature floor must be >= 0");
  if (!flat.hasConstantMomentArms())
    throw std::logic_error("free path rows: the model's moment arms vary with the posture (not supported)");
}

const PathRows::TorqueJetAt& PathRows::torqueJetAt(std::size_t k, const Eigen::VectorXd& c) const {
  if (cached_c_.size() != c.size() || cached_c_ != c) {
    cached_c_ = c;
    cached_.resize(points_.size());
    cached_at_.assign(points_.size(), false);
  }
  if (!cached_at_[k]) {
    TorqueJetAt& at = cached_[k];
    at.tau = flat_.model().pinTree().torqueJet(joint_jet(points_[k], c), at.gradient);
    cached_at_[k] = true;
  }
  return cached_[k];
}

// The rows at z into `values` (point-major, per muscle the reserve row then the four bound rows),
// and with `jacobian` their derivatives through emit(row, column, value) in the pattern's order.
// Buffers sized once per call: the Jacobian is what Ipopt asks for at every iterate.
template <class Emit>
void PathRows::emitRows(const Eigen::VectorXd& z, bool jacobian, double* values, Emit&& emit) const {
  const int n = flat_.numJoints(), m = flat_.numMuscles();
  const Eigen::VectorXd theta = v_.theta(z), c = v_.c(z);
  Eigen::Index widest = 0;
  for (const PathPoint& pt : points_) widest = std::max(widest, static_cast<Eigen::Index>(pt.path_columns.size()));
  // Per point: d(joint jet)/dc, d(torque jet)/dc and d(force jet)/dc (row k m + j: d F_j^(k)), and
  // per muscle d(length jet)/dc; over the point's path columns.
  Eigen::MatrixXd dq(kOrders * n, widest), dtau(3 * n, widest), dtau_k(n, widest), dF(3 * m, widest), dL(3, widest);
  Eigen::MatrixXd path_gradient(3, kOrders * n), tau_plain;
  int row = 0;
  for (std::size_t point = 0; point < points_.size(); ++point) {
    const PathPoint& pt = points_[point];
    const Eigen::MatrixXd q_jet = joint_jet(pt, c);
    const TorqueJetAt* torque = jacobian ? &torqueJetAt(point, c) : nullptr;
    if (!jacobian) tau_plain = flat_.model().pinTree().torqueJet(q_jet);
    const Eigen::MatrixXd F = force_jet(pt, flat_.Ctau(), jacobian ? torque->tau : tau_plain, theta);
    const auto paths = static_cast<Eigen::Index>(pt.path_columns.size());
    const auto thetas = pt.flat.columns.size();
    if (jacobian) {
      joint_jet_slope_into(pt, n, dq);
      dtau.leftCols(paths).noalias() = torque->gradient * dq.leftCols(paths);  // row 3 i + k
      for (int k = 0; k < 3; ++k) {
        for (int i = 0; i < n; ++i) dtau_k.row(i).head(paths) = dtau.row(3 * i + k).head(paths);
        dF.block(k * m, 0, m, paths).noalias() = flat_.Ctau() * dtau_k.leftCols(paths);
      }
    }
    for (int j = 0; j < m; ++j) {
      const muscles::SecondOrderJet path = flat_.pathLengthJet(j, q_jet);
      const MuscleBoundRows bounds = muscle_bound_rows(flat_.model().muscle(j).getParameters(), {F(j, 0), F(j, 1), F(j, 2)},
                                                       path, a_min_[j], jacobian);
      values[row] = F(j, 0) - reserves_[j] - reserve_margin_N(pt);
      for (int k = 0; k < kRowsPerMuscle; ++k) values[row + 1 + k] = bounds.value[static_cast<std::size_t>(k)];
      if (jacobian) {
        // The reserve row: dF / d(theta, c).
        for (std::size_t col = 0; col < thetas; ++col)
          emit(row, pt.flat.columns[col], pt.flat.slope[0](j, static_cast<Eigen::Index>(col)));
        for (Eigen::Index col = 0; col < paths; ++col)
          emit(row, v_.thetas + pt.path_columns[static_cast<std::size_t>(col)], dF(j, col));
        flat_.pathLengthJetGradient(j, q_jet, path_gradient);
        dL.leftCols(paths).noalias() = path_gradient * dq.leftCols(paths);
        for (int k = 0; k < kRowsPerMuscle; ++k) {
          const auto& g = bounds.gradient[static_cast<std::size_t>(k)];
          const auto& pg = bounds.path_gradient[static_cast<std::size_t>(k)];
          for (std::size_t col = 0; col < thetas; ++col)
            emit(row + 1 + k, pt.flat.columns[col], column_derivative(pt.flat, g, j, col));
          for (Eigen::Index col = 0; col < paths; ++col) {
            double d = 0.0;
            for (int o = 0; o < 3; ++o) {
              const auto order = static_cast<std::size_t>(o);
              d += g[order] * dF(o * m + j, col) + pg[order] * dL(o, col);
            }
            emit(row + 1 + k, v_.thetas + pt.path_columns[static_cast<std::size_t>(col)], d);
          }
        }
      }
      row += kRows;
    }
  }
}

std::size_t PathRows::jacobianEntries() const {
  std::size_t entries = 0;
  for (const PathPoint& pt : points_)
    entries += static_cast<std::size_t>(flat_.numMuscles() * kRows) * (pt.flat.columns.size() + pt.path_columns.size());
  return entries;
}

BoundRowsAt PathRows::operator()(const Eigen::VectorXd& z, bool jacobian) const {
  BoundRowsAt out;
  out.value.resize(static_cast<std::size_t>(rows()));
  if (jacobian) out.jacobian.reserve(jacobianEntries());
  emitRows(z, jacobian, out.value.data(), [&](int row, int col, double v) { out.jacobian.emplace_back(row, col, v); });
  for (double v : out.value) out.violation += std::max(0.0, -v);
  return out;
}

void PathRows::evaluateInto(const Eigen::VectorXd& z, double* values, double* jacobian) const {
  emitRows(z, jacobian != nullptr, values, [&jacobian](int, int, double v) { *jacobian++ = v; });
}

namespace {
// Central-difference steps relative to (1 + |entry|): near eps^(1/3), where the truncation and
// rounding errors of a difference of exact gradients balance.
constexpr double kForceJetStep = 1e-5;
}  // namespace

std::vector<int> PathRows::localVariables(const PathPoint& pt) const {
  std::vector<int> out(pt.flat.columns.begin(), pt.flat.columns.end());
  for (int col : pt.path_columns) out.push_back(v_.thetas + col);
  return out;
}

Eigen::MatrixXd PathRows::pointHessian(std::size_t point, const Eigen::VectorXd& theta, const Eigen::VectorXd& c,
                                       const double* lambda, double skip_below) const {
  const PathPoint& pt = points_[point];
  const int n = flat_.numJoints(), m = flat_.numMuscles(), paths = static_cast<int>(pt.path_columns.size());
  const int cols = static_cast<int>(pt.flat.columns.size()), local = cols + paths;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(local, local);
  const Eigen::MatrixXd q_jet = joint_jet(pt, c);
  const TorqueJetAt& torque = torqueJetAt(point, c);
  const Eigen::MatrixXd dq = joint_jet_slope(pt, n);
  const Eigen::MatrixXd dtau = torque.gradient * dq;  // 3N x path columns, row 3 i + k
  const Eigen::MatrixXd F = force_jet(pt, flat_.Ctau(), torque.tau, theta);

  // Per muscle: the multiplier-weighted gradient w of its rows in u = (F jet, L jet), and the
  // curvature in u, J_u^T (d w / du) J_u.
  Eigen::MatrixXd wF = Eigen::MatrixXd::Zero(m, 3);
  Eigen::MatrixXd path_gradient(3, kOrders * n);
  Eigen::Matrix<double, 3, Eigen::Dynamic> J_theta(3, cols);
  Eigen::Matrix<double, 6, Eigen::Dynamic> J_path(6, paths), Hu_J_theta(6, cols), Hu_J_path(6, paths);
  using Vector6 = Eigen::Matrix<double, 6, 1>;
  for (int j = 0; j < m; ++j) {
    const double* l = lambda + j * kRows;
    const muscles::SecondOrderJet L = flat_.pathLengthJet(j, q_jet);
    const auto& p = flat_.model().muscle(j).getParameters();
    auto weighted_gradient = [&](const Vector6& u) {
      const MuscleBoundRows rows = muscle_bound_rows(p, {u[0], u[1], u[2]}, {u[3], u[4], u[5]}, a_min_[j], true);
      Vector6 g = Vector6::Zero();
      for (int r = 0; r < kRowsPerMuscle; ++r)
        for (int o = 0; o < 3; ++o) {
          g[o] += l[1 + r] * rows.gradient[static_cast<std::size_t>(r)][static_cast<std::size_t>(o)];
          g[3 + o] += l[1 + r] * rows.path_gradient[static_cast<std::size_t>(r)][static_cast<std::size_t>(o)];
        }
      return g;
    };
    Vector6 u;
    u << F(j, 0), F(j, 1), F(j, 2), L.value, L.rate, L.acceleration;
    const Vector6 w = weighted_gradient(u);
    wF.row(j) = w.head<3>().transpose();
    wF(j, 0) += l[0];  // the reserve row is F_j itself
    if (std::max({std::abs(l[1]), std::abs(l[2]), std::abs(l[3]), std::abs(l[4])}) <= skip_below) continue;
    Eigen::Matrix<double, 6, 6> Hu;
    for (int i = 0; i < 6; ++i) {
      const double h = kForceJetStep * (1.0 + std::abs(u[i]));
      Vector6 up = u, down = u;
      up[i] += h;
      down[i] -= h;
      Hu.col(i) = (weighted_gradient(up) - weighted_gradient(down)) / (2.0 * h);
    }
    Hu = 0.5 * (Hu + Hu.transpose()).eval();
    // du / d(local variables), by blocks: the force jet over theta (3 x cols; the length jet has
    // no theta columns), and u over the path (6 x paths). Only H's lower triangle is read
    // (emitLagrangianHessian), so its theta-theta, path-theta and path-path blocks are summed,
    // by coefficient-wise products (these blocks are too small for blocked ones to pay).
    for (int k = 0; k < 3; ++k) {
      J_theta.row(k) = pt.flat.slope[static_cast<std::size_t>(k)].row(j);
      J_path.row(k).setZero();
      for (int i = 0; i < n; ++i) J_path.row(k) += flat_.Ctau()(j, i) * dtau.row(3 * i + k);
    }
    flat_.pathLengthJetGradient(j, q_jet, path_gradient);
    J_path.bottomRows<3>() = path_gradient * dq;
    Hu_J_theta = Hu.leftCols<3>() * J_theta;
    H.topLeftCorner(cols, cols) += J_theta.transpose().lazyProduct(Hu_J_theta.topRows<3>());
    H.bottomLeftCorner(paths, cols) += J_path.transpose().lazyProduct(Hu_J_theta);
    Hu_J_path = Hu * J_path;
    H.bottomRightCorner(paths, paths) += J_path.transpose().lazyProduct(Hu_J_path);
  }

  // The torque jet's own curvature in the joint jet, weighted by w: the Hessian of
  // phi(q jet) = sum_jk wF_jk (C_tau tau(q jet))_jk, exact (fourth-order dual numbers), mapped to
  // c by dq. The path lengths have none: with constant moment arms (the constructor's check) they
  // are affine in q.
  if (curvature_ == TorqueCurvature::Exact) {
    const Eigen::MatrixXd Hq = flat_.model().pinTree().torqueJetHessian(q_jet, flat_.Ctau().transpose() * wF);
    H.bottomRightCorner(paths, paths).noalias() += dq.transpose() * Hq * dq;
  }
  return H;
}

std::vector<Eigen::Triplet<double>> PathRows::hessianPattern() const {
  std::vector<Eigen::Triplet<double>> out;
  for (const PathPoint& pt : points_) {
    const std::vector<int> vars = localVariables(pt);
    for (std::size_t a = 0; a < vars.size(); ++a)
      for (std::size_t b = 0; b <= a; ++b) out.emplace_back(std::max(vars[a], vars[b]), std::min(vars[a], vars[b]), 0.0);
  }
  return out;
}

// The lower triangle of each point's block, point after point, through emit(row, column, value).
template <class Emit>
void PathRows::emitLagrangianHessian(const Eigen::VectorXd& z, const double* lambda, Emit&& emit) const {
  const Eigen::VectorXd theta = v_.theta(z), c = v_.c(z);
  const std::size_t per_point = static_cast<std::size_t>(flat_.numMuscles() * kRows);
  double largest = 0.0;  // of the bound rows' multipliers (each muscle's rows after its reserve row)
  for (std::size_t r = 0; r < per_point * points_.size(); ++r)
    if (r % kRows != 0) largest = std::max(largest, std::abs(lambda[r]));
  const double skip_below = inverse_curvature_floor_ * largest;
  for (std::size_t k = 0; k < points_.size(); ++k) {
    const PathPoint& pt = points_[k];
    const std::vector<int> vars = localVariables(pt);
    const Eigen::MatrixXd H = pointHessian(k, theta, c, lambda + k * per_point, skip_below);
    for (std::size_t a = 0; a < vars.size(); ++a)
      for (std::size_t b = 0; b <= a; ++b)
        emit(std::max(vars[a], vars[b]), std::min(vars[a], vars[b]),
             H(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)));
  }
}

std::vector<Eigen::Triplet<double>> PathRows::lagrangianHessian(const Eigen::VectorXd& z,
                                                                const std::vector<double>& lambda) const {
  if (lambda.size() != static_cast<std::size_t>(rows()))
    throw std::invalid_argument("free path rows: one multiplier per row expected");
  std::vector<Eigen::Triplet<double>> out;
  emitLagrangianHessian(z, lambda.data(), [&](int row, int col, double v) { out.emplace_back(row, col, v); });
  return out;
}

void PathRows::lagrangianHessianInto(const Eigen::VectorXd& z, const double* lambda, double* values) const {
  emitLagrangianHessian(z, lambda, [&values](int, int, double v) { *values++ = v; });
}

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

void local_maxima(const std::vector<double>& v, double T, double tolerance, std::vector<double>& times) {
  const std::size_t n = v.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (!(v[i] > tolerance)) continue;
    if ((i == 0 || v[i] >= v[i - 1]) && (i + 1 == n || v[i] >= v[i + 1])) times.push_back(T * static_cast<double>(i) / static_cast<double>(n - 1));
  }
}

}  // namespace flatsos::planner::detail
