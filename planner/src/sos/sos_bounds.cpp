#include "sos/sos_bounds.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>

#include <Eigen/SparseCore>

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/muscles/muscle_inverse.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "flatsos/planner/numerics/simplex_lp.hpp"
#include "numerics/ipopt_support.hpp"

namespace flatsos::planner::detail {

namespace {

namespace fm = flatsos::muscles;
using Ipopt::Index;
using Ipopt::Number;

// The lower bounds of a per muscle.
Eigen::VectorXd activation_minima(const FlatOutputMap& flat, const ExcitationBoundsOptions& o) {
  Eigen::VectorXd a_min(flat.numMuscles());
  for (int j = 0; j < flat.numMuscles(); ++j)
    a_min[j] = o.min_activation > 0.0 ? o.min_activation : flat.model().muscle(j).getParameters().activation_floor;
  return a_min;
}

// Everything about one time point that does not depend on theta: the tendon-force jets are
// F^(k) = base(:, k) + slope[k] * theta(columns), k = 0, 1, 2.
struct BoundPoint {
  double t_s = 0.0;
  Eigen::MatrixXd base;                 // m x 3
  std::vector<int> columns;             // theta entries that move Y's jet here
  std::array<Eigen::MatrixXd, 3> slope; // m x columns
  std::vector<fm::SecondOrderJet> path; // per muscle
};

BoundPoint make_point(const SosSetup& setup, const MusclesAlongPath& mp, double t) {
  const FlatOutputMap& flat = mp.flat;
  const int m = flat.numMuscles(), p = flat.numFlatOutputs();
  const Jet q_jet = mp.path.jet(t, 5);
  const TorqueJet tau = flat.torqueJet(mp.workspace, q_jet);
  BoundPoint bp;
  bp.t_s = t;
  bp.base.resize(m, 3);
  std::array<Eigen::MatrixXd, 3> full;
  for (int k = 0; k < 3; ++k) {
    const Eigen::RowVectorXd row = setup.basis.derivativeRow(t, k);
    Eigen::VectorXd y_particular(p);
    Eigen::MatrixXd dY = Eigen::MatrixXd::Zero(p, setup.free_coefficients);
    for (int l = 0; l < p; ++l) {
      const auto& out = setup.outputs[static_cast<std::size_t>(l)];
      y_particular[l] = row.dot(out.particular);
      if (out.nullspace.cols()) dY.block(l, out.offset, 1, out.nullspace.cols()) = row * out.nullspace;
    }
    bp.base.col(k) = flat.Ctau() * tau.tau.col(k) + flat.CY() * y_particular;
    full[static_cast<std::size_t>(k)] = flat.CY() * dY;
  }
  for (int c = 0; c < setup.free_coefficients; ++c)
    if (full[0].col(c).any() || full[1].col(c).any() || full[2].col(c).any()) bp.columns.push_back(c);
  for (int k = 0; k < 3; ++k) {
    auto& s = bp.slope[static_cast<std::size_t>(k)];
    s.resize(m, static_cast<Eigen::Index>(bp.columns.size()));
    for (std::size_t c = 0; c < bp.columns.size(); ++c) s.col(static_cast<Eigen::Index>(c)) = full[static_cast<std::size_t>(k)].col(bp.columns[c]);
  }
  for (int j = 0; j < m; ++j) bp.path.push_back(flat.pathLengthJet(j, q_jet));
  return bp;
}

// The bound rows of one muscle at one point, each ">= 0": a - a_min, 1 - a, and the two margins
// of muscles::excitation_bound_margins for 0 <= n <= 1 (smooth in a and da/dt, defined where n
// is not), with their gradients in the point's tendon-force jet.
constexpr int kRowsPerMuscle = 4;
constexpr double kBoundMargin = 1e-9;
struct MuscleBoundRows {
  bool defined = false;  // false: slack tendon or no force capacity (no a, no n)
  std::array<double, kRowsPerMuscle> value{};
  std::array<fm::TendonForceJetGradient, kRowsPerMuscle> gradient{};
};

MuscleBoundRows bound_rows(const FlatOutputMap& flat, const BoundPoint& bp, int j, double a_min,
                           const Eigen::Ref<const Eigen::VectorXd>& theta, bool gradients) {
  double F[3];
  for (int k = 0; k < 3; ++k) {
    double v = bp.base(j, k);
    const auto& s = bp.slope[static_cast<std::size_t>(k)];
    for (std::size_t c = 0; c < bp.columns.size(); ++c) v += s(j, static_cast<Eigen::Index>(c)) * theta[bp.columns[c]];
    F[k] = v;
  }
  const fm::MuscleParameters& p = flat.model().muscle(j).getParameters();
  const fm::MuscleInverse inv = fm::invert_muscle(p, {F[0], F[1], F[2]}, bp.path[static_cast<std::size_t>(j)], gradients);
  MuscleBoundRows rows;
  if (inv.stage != fm::MuscleInverse::Stage::Complete) return rows;
  rows.defined = true;
  const fm::ExcitationBoundMargins m = fm::excitation_bound_margins(p, inv.activation, inv.activation_rate_per_s);
  // Imposed with a margin of 1e-9, so that rounding leaves the plan inside, not at -1e-14.
  rows.value = {inv.activation - a_min - kBoundMargin, 1.0 - inv.activation - kBoundMargin, m.lower - kBoundMargin,
                m.upper - kBoundMargin};
  if (gradients)
    for (std::size_t o = 0; o < 3; ++o) {
      const double da = inv.activation_gradient[o], dadot = inv.activation_rate_gradient[o];
      rows.gradient[0][o] = da;
      rows.gradient[1][o] = -da;
      rows.gradient[2][o] = m.lower_d_activation * da + m.lower_d_rate_s * dadot;
      rows.gradient[3][o] = m.upper_d_activation * da + m.upper_d_rate_s * dadot;
    }
  return rows;
}

// d(row)/d theta over the point's columns.
double column_derivative(const BoundPoint& bp, const fm::TendonForceJetGradient& g, int j, std::size_t c) {
  double v = 0.0;
  for (std::size_t o = 0; o < 3; ++o) v += g[o] * bp.slope[o](j, static_cast<Eigen::Index>(c));
  return v;
}

// The Ipopt problem (the bounds' second opinion): minimize cost . theta subject to the reserves'
// exchange rows (linear) and the bound rows at the bound points.
class BoundedSopNlp : public Ipopt::TNLP {
 public:
  BoundedSopNlp(const SosSetup& setup, const FlatOutputMap& flat, const std::vector<BoundPoint>& points,
                const Eigen::VectorXd& a_min, const Eigen::VectorXd& start)
      : setup_(setup), flat_(flat), points_(points), a_min_(a_min), start_(start) {
    const Eigen::MatrixXd& G = setup_.lp.G;
    for (Eigen::Index r = 0; r < G.rows(); ++r)
      for (Eigen::Index c = 0; c < G.cols(); ++c)
        if (G(r, c) != 0.0) linear_.push_back({static_cast<Index>(r), static_cast<Index>(c)});
  }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac, Index& nnz_h, IndexStyleEnum& style) override {
    n = setup_.free_coefficients;
    m = static_cast<Index>(setup_.lp.G.rows() + kRowsPerMuscle * points_.size() * muscles());
    nnz_jac = static_cast<Index>(linear_.size());
    for (const auto& bp : points_) nnz_jac += static_cast<Index>(kRowsPerMuscle * muscles() * bp.columns.size());
    nnz_h = 0;
    style = C_STYLE;
    return true;
  }
  bool get_bounds_info(Index n, Number* xl, Number* xu, Index, Number* gl, Number* gu) override {
    for (Index i = 0; i < n; ++i) xl[i] = setup_.lp.x_lower[i], xu[i] = setup_.lp.x_upper[i];
    Index r = 0;
    for (; r < setup_.lp.G.rows(); ++r) gl[r] = setup_.lp.row_lower[r], gu[r] = 1e19;
    for (std::size_t i = 0; i < points_.size(); ++i)
      for (int j = 0; j < muscles(); ++j) {
        for (int k = 0; k < kRowsPerMuscle; ++k) gl[r] = 0.0, gu[r++] = 1e19;
      }
    return true;
  }
  bool get_starting_point(Index n, bool init_x, Number* x, bool, Number*, Number*, Index, bool, Number*) override {
    if (init_x)
      for (Index i = 0; i < n; ++i) x[i] = start_[i];
    return true;
  }
  bool eval_f(Index n, const Number* x, bool, Number& f) override {
    f = setup_.lp.cost.dot(Eigen::Map<const Eigen::VectorXd>(x, n));
    return true;
  }
  bool eval_grad_f(Index n, const Number*, bool, Number* g) override {
    Eigen::Map<Eigen::VectorXd>(g, n) = setup_.lp.cost;
    return true;
  }
  bool eval_g(Index n, const Number* x, bool, Index, Number* g) override {
    const Eigen::Map<const Eigen::VectorXd> theta(x, n);
    const Eigen::Index linear_rows = setup_.lp.G.rows();
    Eigen::Map<Eigen::VectorXd>(g, linear_rows) = setup_.lp.G * theta;
    Index r = static_cast<Index>(linear_rows);
    for (const auto& bp : points_)
      for (int j = 0; j < muscles(); ++j) {
        const MuscleBoundRows rows = bound_rows(flat_, bp, j, a_min_[j], theta, false);
        if (!rows.defined) return false;
        for (double v : rows.value) g[r++] = v;
      }
    return true;
  }
  bool eval_jac_g(Index n, const Number* x, bool, Index, Index, Index* irow, Index* jcol, Number* values) override {
    Index k = 0;
    if (!values) {
      for (const auto& [r, c] : linear_) irow[k] = r, jcol[k++] = c;
      Index r = static_cast<Index>(setup_.lp.G.rows());
      for (const auto& bp : points_)
        for (int j = 0; j < muscles(); ++j, r += kRowsPerMuscle)
          for (int which = 0; which < kRowsPerMuscle; ++which)
            for (int c : bp.columns) irow[k] = r + which, jcol[k++] = c;
      return true;
    }
    const Eigen::Map<const Eigen::VectorXd> theta(x, n);
    for (const auto& [r, c] : linear_) values[k++] = setup_.lp.G(r, c);
    for (const auto& bp : points_)
      for (int j = 0; j < muscles(); ++j) {
        const MuscleBoundRows rows = bound_rows(flat_, bp, j, a_min_[j], theta, true);
        if (!rows.defined) return false;
        for (const auto& grad : rows.gradient)
          for (std::size_t c = 0; c < bp.columns.size(); ++c) values[k++] = column_derivative(bp, grad, j, c);
      }
    return true;
  }
  bool eval_h(Index, const Number*, bool, Number, Index, const Number*, bool, Index, Index*, Index*, Number*) override {
    return false;  // limited-memory quasi-Newton
  }
  void finalize_solution(Ipopt::SolverReturn, Index n, const Number* x, const Number*, const Number*, Index,
                         const Number*, const Number*, Number, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    x_ = Eigen::Map<const Eigen::VectorXd>(x, n);
  }

  Eigen::VectorXd x_;

 private:
  int muscles() const { return flat_.numMuscles(); }

  const SosSetup& setup_;
  const FlatOutputMap& flat_;
  const std::vector<BoundPoint>& points_;
  const Eigen::VectorXd& a_min_;
  const Eigen::VectorXd& start_;
  std::vector<std::pair<Index, Index>> linear_;
};

// ---- Sequential linear programming with a trust region (the default bounds solver) ----
// The cost is linear and the optimum sits where as many constraints are active as there are free
// coefficients, so linearizing the bound rows at theta and solving the LP inside a box
// |d| <= Delta converges like Newton's method near the solution. Every row is elastic (a slack
// priced at `penalty` per unit), which keeps each LP feasible and makes the l1 merit
//   phi(theta) = cost . theta + penalty (sum of bound-row violations + reserve-row violations in N)
// an exact penalty once the penalty exceeds every multiplier; steps are accepted by the ratio of
// actual to predicted merit decrease. Near t = 0 the initial state pins the flat outputs, rows
// move little per newton and their multipliers are large: the penalty grows tenfold whenever the
// iteration settles with rows still violated.
constexpr double kInitialPenalty = 1e4, kMaxPenalty = 1e12;
constexpr double kRowTolerance = 1e-9;  // violation left by the LP's own tolerance

struct BoundRowsAt {
  std::vector<double> value;  // per point, muscle, row; -inf where undefined
  std::vector<Eigen::Triplet<double>> jacobian;  // (row, theta column, derivative)
  double violation = 0.0;     // sum of max(0, -value)
  bool defined = true;
};

BoundRowsAt evaluate_rows(const FlatOutputMap& flat, const std::vector<BoundPoint>& points, const Eigen::VectorXd& a_min,
                          const Eigen::VectorXd& theta, bool jacobian) {
  BoundRowsAt out;
  const int m = flat.numMuscles();
  out.value.reserve(points.size() * static_cast<std::size_t>(m * kRowsPerMuscle));
  int row = 0;
  for (const auto& bp : points)
    for (int j = 0; j < m; ++j) {
      const MuscleBoundRows rows = bound_rows(flat, bp, j, a_min[j], theta, jacobian);
      for (int k = 0; k < kRowsPerMuscle; ++k, ++row) {
        if (!rows.defined) {
          out.value.push_back(-std::numeric_limits<double>::infinity());
          out.defined = false;
          continue;
        }
        out.value.push_back(rows.value[static_cast<std::size_t>(k)]);
        out.violation += std::max(0.0, -rows.value[static_cast<std::size_t>(k)]);
        if (jacobian)
          for (std::size_t c = 0; c < bp.columns.size(); ++c)
            out.jacobian.emplace_back(row, bp.columns[c], column_derivative(bp, rows.gradient[static_cast<std::size_t>(k)], j, c));
      }
    }
  return out;
}

double reserve_violation_N(const LinearProgram& lp, const Eigen::VectorXd& theta) {
  if (lp.G.rows() == 0) return 0.0;
  return (lp.row_lower - lp.G * theta).cwiseMax(0.0).sum();
}

struct SlpOutcome {
  bool converged = false;
  bool rows_violated = false;  // settled at the largest penalty with imposed rows still violated
  int iterations = 0, lp_pivots = 0;
  std::string failure;
};

SlpOutcome solve_bounds_by_slp(const SosSetup& setup, const FlatOutputMap& flat, const std::vector<BoundPoint>& points,
                               const Eigen::VectorXd& a_min, double reserve_margin_N, Eigen::VectorXd& theta, double& radius,
                               int max_iterations) {
  SlpOutcome out;
  const LinearProgram& lp = setup.lp;
  const Eigen::Index n = setup.free_coefficients;
  BoundRowsAt rows = evaluate_rows(flat, points, a_min, theta, true);
  if (!rows.defined) {
    out.failure = "the start leaves the muscles' domain at a bound point";
    return out;
  }
  double penalty = kInitialPenalty;
  auto merit = [&](const Eigen::VectorXd& x, const BoundRowsAt& r) {
    return lp.cost.dot(x) + penalty * (r.violation + reserve_violation_N(lp, x));
  };
  double phi = merit(theta, rows);
  for (; out.iterations < max_iterations; ++out.iterations) {
    // Rows that cannot reach zero inside the box are left out of this LP.
    std::vector<double> row_norm(rows.value.size(), 0.0);
    for (const auto& t : rows.jacobian) row_norm[static_cast<std::size_t>(t.row())] += std::abs(t.value());
    std::vector<int> bound_rows_in;
    for (std::size_t i = 0; i < rows.value.size(); ++i)
      if (rows.value[i] - radius * row_norm[i] < 0.0) bound_rows_in.push_back(static_cast<int>(i));
    const Eigen::VectorXd reserve_value = lp.G.rows() ? Eigen::VectorXd(lp.G * theta - lp.row_lower) : Eigen::VectorXd();
    std::vector<int> reserve_rows_in;
    for (Eigen::Index r = 0; r < lp.G.rows(); ++r)
      if (reserve_value[r] - radius * lp.G.row(r).cwiseAbs().sum() < 0.0) reserve_rows_in.push_back(static_cast<int>(r));
    // Variables: d (n), then a slack for each row violated at theta (d = 0 meets the others, so
    // the LP stays feasible with far fewer columns).
    std::vector<double> lp_lower;
    std::vector<Eigen::Triplet<double>> entries;
    int slacks = 0;
    auto add_row = [&](double lower) {
      const int r = static_cast<int>(lp_lower.size());
      lp_lower.push_back(lower);
      if (lower > 0.0) entries.emplace_back(r, n + slacks++, 1.0);
      return r;
    };
    std::vector<int> lp_row_of(rows.value.size(), -1);
    for (int i : bound_rows_in) lp_row_of[static_cast<std::size_t>(i)] = add_row(-rows.value[static_cast<std::size_t>(i)]);
    for (const auto& t : rows.jacobian)
      if (const int r = lp_row_of[static_cast<std::size_t>(t.row())]; r >= 0) entries.emplace_back(r, t.col(), t.value());
    for (int r : reserve_rows_in) {
      const int row = add_row(-reserve_value[r]);
      for (Eigen::Index c = 0; c < n; ++c)
        if (lp.G(r, c) != 0.0) entries.emplace_back(row, c, lp.G(r, c));
    }
    const Eigen::Index vars = n + slacks, lp_rows = static_cast<Eigen::Index>(lp_lower.size());
    SparseLinearProgram sub;
    sub.cost.resize(vars);
    sub.cost.head(n) = lp.cost;
    sub.cost.tail(slacks).setConstant(penalty);
    sub.x_lower.resize(vars);
    sub.x_upper.resize(vars);
    for (Eigen::Index i = 0; i < n; ++i) {
      sub.x_lower[i] = std::max(-radius, lp.x_lower[i] - theta[i]);
      sub.x_upper[i] = std::min(radius, lp.x_upper[i] - theta[i]);
    }
    sub.x_lower.tail(slacks).setZero();
    sub.x_upper.tail(slacks).setConstant(1e19);
    sub.row_lower = Eigen::Map<const Eigen::VectorXd>(lp_lower.data(), lp_rows);
    sub.row_upper = Eigen::VectorXd::Constant(lp_rows, 1e19);
    sub.G.resize(lp_rows, vars);
    sub.G.setFromTriplets(entries.begin(), entries.end());
    const LinearProgramResult step = solve_linear_program_simplex(sub);
    out.lp_pivots += step.iterations;
    if (step.status != SolveStatus::Solved) {
      out.failure = "a step LP was not solved (Clp: " + step.solver_status + ")";
      return out;
    }
    const Eigen::VectorXd d = step.x.head(n);
    // The predicted decrease from the linearized rows at d itself, not from the LP's slacks:
    // those carry the LP's own feasibility tolerance, which the penalty would magnify. The rows
    // left out are >= 0 at 0 and at d in the linearization: they add nothing.
    Eigen::VectorXd linear_at_d = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(rows.value.size()));
    for (const auto& t : rows.jacobian) linear_at_d[t.row()] += t.value() * d[t.col()];
    double violation_now = 0.0, violation_at_d = 0.0;
    for (int i : bound_rows_in) {
      const double v = rows.value[static_cast<std::size_t>(i)];
      violation_now += std::max(0.0, -v);
      violation_at_d += std::max(0.0, -(v + linear_at_d[i]));
    }
    for (int r : reserve_rows_in) {
      violation_now += std::max(0.0, -reserve_value[r]);
      violation_at_d += std::max(0.0, -(reserve_value[r] + lp.G.row(r).dot(d)));
    }
    const double predicted = penalty * (violation_now - violation_at_d) - lp.cost.dot(d);
    const double step_size = d.size() ? d.cwiseAbs().maxCoeff() : 0.0;
    // Settled: nothing left to gain, or steps far below any meaningful force. Done when every
    // imposed row holds (bound rows to their margin, reserve rows to half the exchange margin);
    // otherwise the violated rows' multipliers exceed the penalty: raise it and go on.
    auto settle = [&]() {
      const double worst_row = *std::min_element(rows.value.begin(), rows.value.end());
      const double worst_reserve = lp.G.rows() ? (lp.G * theta - lp.row_lower).minCoeff() : 0.0;
      const bool rows_hold = worst_row >= -kBoundMargin && worst_reserve >= -0.5 * reserve_margin_N;
      out.rows_violated = !rows_hold;
      if (rows_hold || penalty >= kMaxPenalty) return true;
      penalty *= 10.0;
      phi = merit(theta, rows);
      return false;
    };
    if (predicted <= 1e-12 * (1.0 + std::abs(phi))) {
      if (settle()) {
        out.converged = true;
        return out;
      }
      continue;
    }
    const Eigen::VectorXd trial = theta + d;
    BoundRowsAt trial_rows = evaluate_rows(flat, points, a_min, trial, true);
    const double trial_phi = trial_rows.defined ? merit(trial, trial_rows) : std::numeric_limits<double>::infinity();
    const double ratio = (phi - trial_phi) / predicted;
    if (ratio < 0.25) radius = 0.5 * step_size;
    else if (ratio > 0.75 && step_size >= 0.99 * radius) radius *= 2.0;
    const bool accepted = ratio > 0.1;
    if (accepted) {
      theta = trial;
      rows = std::move(trial_rows);
      phi = trial_phi;
      // Near the solution steps shrink quadratically: a box a little larger than the last step
      // keeps only the rows that can become active in the next LP (far smaller LPs).
      radius = std::min(radius, std::max(10.0 * step_size, 1e-6 * (1.0 + theta.cwiseAbs().maxCoeff())));
    }
    const double scale = 1.0 + theta.cwiseAbs().maxCoeff();
    if ((accepted && step_size <= 1e-7 * scale) || radius < 1e-10 * scale) {
      if (settle()) {
        out.converged = true;
        return out;
      }
      radius = std::max(radius, 1e-6 * scale);
    }
  }
  out.failure = "the sequential LP did not converge in " + std::to_string(max_iterations) + " iterations";
  return out;
}

// The bounds on the check grid for the flat outputs of theta: per grid time the largest excess
// over any muscle's bounds (0 inside; +inf where the inverse is undefined), and the worst one.
struct GridExcess {
  std::vector<double> excess;
  double worst = 0.0;
  std::string worst_text;
};

GridExcess grid_excess(const SosSetup& setup, const MusclesAlongPath& mp, const std::vector<TorqueJet>& jets,
                       const Eigen::VectorXd& a_min, const Eigen::VectorXd& theta, int points) {
  const SplineTrajectory Y = flat_outputs_of(setup, theta);
  const FlatOutputMap& flat = mp.flat;
  const double h = setup.duration_s / (points - 1);
  GridExcess out;
  out.excess.assign(static_cast<std::size_t>(points), 0.0);
  MusclePoint point;
  Jet q_jet(flat.numJoints(), 3), y_jet(flat.numFlatOutputs(), 3);
  for (int i = 0; i < points; ++i) {
    const double t = h * i;
    mp.path.jetInto(t, q_jet);
    Y.jetInto(t, y_jet);
    flat.inverseFromTorque(q_jet, jets[static_cast<std::size_t>(i)], y_jet, point);
    for (int j = 0; j < flat.numMuscles(); ++j) {
      const double a = point.activation[j], n = point.excitation[j];
      double e = std::max({a_min[j] - a, a - 1.0, -n, n - 1.0, 0.0});
      const DomainViolation::Kind kind = point.domain_violation[static_cast<std::size_t>(j)].kind;
      if (!std::isfinite(a) || !std::isfinite(n) || kind == DomainViolation::Kind::SlackTendon ||
          kind == DomainViolation::Kind::NoForceCapacity || kind == DomainViolation::Kind::ExcitationUnattainable)
        e = std::numeric_limits<double>::infinity();
      out.excess[static_cast<std::size_t>(i)] = std::max(out.excess[static_cast<std::size_t>(i)], e);
      if (e > out.worst) {
        out.worst = e;
        std::ostringstream why;
        why << "muscle '" << flat.model().description().muscles[static_cast<std::size_t>(j)].parameters.name << "' at t = " << t
            << " s: activation " << a << ", excitation " << n;
        out.worst_text = why.str();
      }
    }
  }
  return out;
}

// Grid times where the excess is a local maximum above the tolerance.
std::vector<double> violated_times(const GridExcess& g, double h, double tolerance) {
  std::vector<double> times;
  const std::size_t n = g.excess.size();
  for (std::size_t i = 0; i < n; ++i) {
    const double e = g.excess[i];
    if (!(e > tolerance)) continue;
    const bool left = i == 0 || e >= g.excess[i - 1], right = i + 1 == n || e >= g.excess[i + 1];
    if (left && right) times.push_back(h * static_cast<double>(i));
  }
  return times;
}

}  // namespace

bool impose_excitation_bounds(SosSetup& setup, const MusclesAlongPath& mp, const SosProgramOptions& o,
                              Eigen::VectorXd& theta, SosProgramResult& result) {
  const Stopwatch wall;
  const ExcitationBoundsOptions& bo = o.bounds;
  if (bo.check_points < 2) throw std::invalid_argument("SOS program: bounds need at least 2 check points");
  const FlatOutputMap& flat = mp.flat;
  const Eigen::VectorXd a_min = activation_minima(flat, bo);
  const double h = setup.duration_s / (bo.check_points - 1);
  const std::vector<TorqueJet> jets =
      flat.torqueJetsOnGrid(mp.workspace, [&](double t) { return mp.path.jet(t, 3); }, 0.0, h, bo.check_points);

  GridExcess excess = grid_excess(setup, mp, jets, a_min, theta, bo.check_points);
  result.max_bound_excess = excess.worst;
  if (excess.worst <= bo.tolerance) {
    result.bounds_seconds = wall.seconds();
    return true;
  }
  result.bounds_imposed = true;
  std::vector<BoundPoint> points;
  auto add_point = [&](double t) {
    for (const auto& bp : points)
      if (std::abs(bp.t_s - t) < 1e-9) return false;
    points.push_back(make_point(setup, mp, t));
    return true;
  };
  const int uniform = bo.initial_points_per_span * setup.basis.spans();
  for (int i = 0; i <= uniform; ++i) add_point(setup.duration_s * i / std::max(uniform, 1));
  for (double t : violated_times(excess, h, bo.tolerance)) add_point(t);

  double radius = 0.1 * (1.0 + theta.cwiseAbs().maxCoeff());
  bool last_rows_violated = false;
  for (int round = 0; round < bo.max_rounds; ++round) {
    result.bound_rounds = round + 1;
    result.lp_points = build_exchange_rows(setup, o.feasibility_margin_N);
    result.bound_points = static_cast<int>(points.size());
    if (bo.solver == BoundsSolver::SequentialLp) {
      const SlpOutcome slp = solve_bounds_by_slp(setup, flat, points, a_min, o.feasibility_margin_N, theta, radius, bo.max_slp_iterations);
      result.bound_slp_iterations += slp.iterations;
      result.simplex_pivots += slp.lp_pivots;
      if (!slp.converged) {
        result.status = SolveStatus::Failed;
        result.message = "the bounds were not met: " + slp.failure;
        result.bounds_seconds = wall.seconds();
        return false;
      }
      last_rows_violated = slp.rows_violated;
    } else {
      auto app = make_ipopt(1e-8, bo.max_ipopt_iterations);
      app->Options()->SetStringValue("hessian_approximation", "limited-memory");
      app->Options()->SetStringValue("mu_strategy", "adaptive");
      app->Options()->SetNumericValue("bound_relax_factor", 0.0);
      app->Options()->SetNumericValue("constr_viol_tol", 1e-9);
      Ipopt::SmartPtr<BoundedSopNlp> nlp = new BoundedSopNlp(setup, flat, points, a_min, theta);
      const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::SmartPtr<Ipopt::TNLP>(GetRawPtr(nlp)));
      if (Ipopt::SmartPtr<Ipopt::SolveStatistics> stats = app->Statistics(); IsValid(stats))
        result.ipopt_iterations += stats->IterationCount();
      ++result.ipopt_calls;
      if (!ipopt_solved(status)) {
        const GridExcess at = nlp->x_.size() ? grid_excess(setup, mp, jets, a_min, nlp->x_, bo.check_points) : excess;
        result.status = ipopt_infeasible(status) ? SolveStatus::Infeasible : SolveStatus::Failed;
        result.message = std::string(ipopt_infeasible(status) ? "infeasible" : "failed") +
                         ": no flat outputs in this basis keep every excitation in [0, 1] and activation in [a_min, 1] "
                         "with the reserves (Ipopt: " + ipopt_status_name(status) + "); where it stopped, " + at.worst_text;
        result.bounds_seconds = wall.seconds();
        return false;
      }
      theta = nlp->x_;
    }
    double min_reserve = 0.0;
    const bool reserves_added = add_violated_points(setup, theta, min_reserve);
    result.min_constraint_value_N = min_reserve;
    excess = grid_excess(setup, mp, jets, a_min, theta, bo.check_points);
    result.max_bound_excess = excess.worst;
    bool bounds_added = false;
    // Every local maximum of the excess joins, not only those above the tolerance: along an arc
    // where a bound is active the dips between imposed points come back one by one otherwise.
    for (double t : violated_times(excess, h, 0.0)) bounds_added |= add_point(t);
    if (!reserves_added && excess.worst <= bo.tolerance) {
      result.bounds_seconds = wall.seconds();
      return true;
    }
    if (!reserves_added && !bounds_added) break;  // violations at points already imposed: tolerance
  }
  result.bounds_seconds = wall.seconds();
  if (last_rows_violated) {
    // A local minimum of the violation, even at a penalty of 1e12 per unit: the flat outputs of
    // this basis cannot meet the bounds along this joint path (from this start).
    result.status = SolveStatus::Infeasible;
    result.message = "infeasible: no flat outputs in this basis keep every excitation in [0, 1] and activation in "
                     "[a_min, 1] with the reserves along this joint path";
    result.Y = flat_outputs_of(setup, theta);  // the closest plan, for the caller's diagnosis
    return false;
  }
  result.status = SolveStatus::Failed;
  result.message = "the bounded exchange did not converge in " + std::to_string(result.bound_rounds) +
                   " rounds (worst bound excess " + std::to_string(excess.worst) + ": " + excess.worst_text + ")";
  return false;
}

}  // namespace flatsos::planner::detail
