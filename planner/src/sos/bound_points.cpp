#include "sos/bound_points.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <boost/math/tools/minima.hpp>

#include "flatsos/muscles/hill_laws.hpp"

namespace flatsos::planner::detail {

namespace fm = flatsos::muscles;

namespace {

// The point's tendon-force jet as base + slope theta through the coupling at this posture
// (flat_outputs.hpp, ForceJetMap): v_k = C_tau tau^(k) + C_Y Y^(k), mixed by the W's. Without a
// torque jet, only the flat outputs' part.
BoundPoint point_through(const SosSetup& setup, const ForceJetMap& map, double t, const Eigen::MatrixXd* tau) {
  const Eigen::Index m = map.CY.rows(), p = map.CY.cols();
  BoundPoint bp;
  bp.t_s = t;
  std::array<Eigen::MatrixXd, 3> base, full;
  for (int k = 0; k < 3; ++k) {
    const Eigen::RowVectorXd row = setup.basis.derivativeRow(t, k);
    Eigen::VectorXd y_particular(p);
    Eigen::MatrixXd dY = Eigen::MatrixXd::Zero(p, setup.free_coefficients);
    for (Eigen::Index l = 0; l < p; ++l) {
      const auto& out = setup.outputs[static_cast<std::size_t>(l)];
      y_particular[l] = row.dot(out.particular);
      if (out.nullspace.cols()) dY.block(l, out.offset, 1, out.nullspace.cols()) = row * out.nullspace;
    }
    base[static_cast<std::size_t>(k)] = map.CY * y_particular;
    if (tau) base[static_cast<std::size_t>(k)] += map.Ctau * tau->col(k);
    full[static_cast<std::size_t>(k)] = map.CY * dY;
  }
  map.mix(base[0], base[1], base[2]);
  map.mix(full[0], full[1], full[2]);
  bp.base.resize(m, 3);
  for (int k = 0; k < 3; ++k) bp.base.col(k) = base[static_cast<std::size_t>(k)];
  for (int c = 0; c < setup.free_coefficients; ++c)
    if (full[0].col(c).any() || full[1].col(c).any() || full[2].col(c).any()) bp.columns.push_back(c);
  for (int k = 0; k < 3; ++k) {
    auto& s = bp.slope[static_cast<std::size_t>(k)];
    s.resize(m, static_cast<Eigen::Index>(bp.columns.size()));
    for (std::size_t c = 0; c < bp.columns.size(); ++c) s.col(static_cast<Eigen::Index>(c)) = full[static_cast<std::size_t>(k)].col(bp.columns[c]);
  }
  return bp;
}

}  // namespace

BoundPoint flat_output_point(const SosSetup& setup, const FlatOutputMap& flat, double t) {
  ForceJetMap constant;  // a free joint path: constant moment arms (FlatOutputMap::CY says so otherwise)
  constant.Ctau = flat.Ctau();
  constant.CY = flat.CY();
  return point_through(setup, constant, t, nullptr);
}

BoundPoint make_point(const SosSetup& setup, const MusclesAlongPath& mp, double t) {
  const FlatOutputMap& flat = mp.flat;
  const Jet q_jet = mp.path.jet(t, 5);
  const TorqueJet tau = flat.torqueJet(mp.workspace, q_jet);
  BoundPoint bp = point_through(setup, flat.forceJetMap(q_jet), t, &tau.tau);
  for (int j = 0; j < flat.numMuscles(); ++j) bp.path.push_back(flat.pathLengthJet(j, q_jet));
  return bp;
}

namespace {

bool undefined(const MusclePoint& point, int j) {
  const DomainViolation::Kind kind = point.domain_violation[static_cast<std::size_t>(j)].kind;
  return !std::isfinite(point.activation[j]) || !std::isfinite(point.excitation[j]) ||
         kind == DomainViolation::Kind::SlackTendon || kind == DomainViolation::Kind::NoForceCapacity ||
         kind == DomainViolation::Kind::ExcitationUnattainable;
}

// Muscle j's excess over its bounds at an inverse-map point (0 inside, +inf where the inverse is
// undefined): what the plan reports.
double excess_of(const MusclePoint& point, int j, double a_min) {
  if (undefined(point, j)) return std::numeric_limits<double>::infinity();
  const double a = point.activation[j], n = point.excitation[j];
  return std::max({a_min - a, a - 1.0, -n, n - 1.0, 0.0});
}

// The same signed, by the rows' smooth margins (muscles::excitation_bound_margins): negative
// inside. n alone would not do: for a above beta / (1 - beta) the lower bound is the fastest
// deactivation any excitation gives, and a plan can demand more while n looks far from 0 (it
// then has no real root). Where the force inverse is undefined, +inf.
double signed_margin_excess(const fm::MuscleParameters& p, const MusclePoint& point, int j, double a_min) {
  const double a = point.activation[j];
  const DomainViolation::Kind kind = point.domain_violation[static_cast<std::size_t>(j)].kind;
  if (!std::isfinite(a) || !std::isfinite(point.activation_rate_per_s[j]) || kind == DomainViolation::Kind::SlackTendon ||
      kind == DomainViolation::Kind::NoForceCapacity)
    return std::numeric_limits<double>::infinity();
  const fm::ExcitationBoundMargins m = fm::excitation_bound_margins(p, a, point.activation_rate_per_s[j]);
  return std::max({a_min - a, a - 1.0, -m.lower, -m.upper});
}

void note_worst(const FlatOutputMap& flat, const MusclePoint& point, int j, double t, double e, GridExcess& out) {
  if (!(e > out.worst)) return;
  out.worst = e;
  std::ostringstream why;
  why << "muscle '" << flat.model().description().muscles[static_cast<std::size_t>(j)].parameters.name << "' at t = " << t
      << " s: activation " << point.activation[j] << ", excitation " << point.excitation[j];
  out.worst_text = why.str();
}

// The between-points search of grid_excess (bound_rows.hpp). `margins`: per grid time and muscle
// the signed excess.
void search_between_points(const SosSetup& setup, const MusclesAlongPath& mp, const SplineTrajectory& Y,
                           const Eigen::VectorXd& a_min, const Eigen::MatrixXd& margins, double h, GridExcess& out) {
  const FlatOutputMap& flat = mp.flat;
  const Eigen::Index n = margins.rows();
  Jet q_jet(flat.numJoints(), 5), y_jet(flat.numFlatOutputs(), 3);
  MusclePoint point;
  auto inverse_at = [&](double t) {
    mp.path.jetInto(t, q_jet);
    Y.jetInto(t, y_jet);
    flat.inverseFromTorque(q_jet, flat.torqueJet(mp.workspace, q_jet), y_jet, point);
  };
  // Brent's tolerance in t: 2^-30 of the time (3e-9 s at 3 s), far below any feature the
  // inverse resolves; its iterations are a safeguard only.
  constexpr int kBits = 30;
  constexpr std::uintmax_t kIterations = 60;
  for (int j = 0; j < flat.numMuscles(); ++j)
    for (Eigen::Index i = 0; i < n; ++i) {
      const double e = margins(i, j);
      if (!std::isfinite(e) || e < -kNearBound) continue;
      if ((i > 0 && margins(i - 1, j) > e) || (i + 1 < n && margins(i + 1, j) > e)) continue;
      const double lo = h * static_cast<double>(std::max<Eigen::Index>(i - 1, 0));
      const double hi = std::min(h * static_cast<double>(i + 1), setup.duration_s);
      const fm::MuscleParameters& p = flat.model().muscle(j).getParameters();
      auto negative_excess = [&](double t) {
        inverse_at(t);
        const double v = signed_margin_excess(p, point, j, a_min[j]);
        return std::isfinite(v) ? -v : -std::numeric_limits<double>::max();
      };
      std::uintmax_t iterations = kIterations;
      const auto best = boost::math::tools::brent_find_minima(negative_excess, lo, hi, kBits, iterations);
      const double t = best.first, excess = -best.second;
      if (!(excess > 0.0) || !(excess > e)) continue;
      inverse_at(t);
      out.between.push_back({t, excess});
      note_worst(flat, point, j, t, std::max(excess, excess_of(point, j, a_min[j])), out);
    }
  std::sort(out.between.begin(), out.between.end(),
            [](const GridExcess::BetweenPoints& l, const GridExcess::BetweenPoints& r) { return l.t_s < r.t_s; });
}

}  // namespace

GridExcess grid_excess(const SosSetup& setup, const MusclesAlongPath& mp, const std::vector<TorqueJet>& jets,
                       const Eigen::VectorXd& a_min, const Eigen::VectorXd& theta, int points, int stride) {
  if (stride < 1 || (points - 1) % stride != 0) throw std::logic_error("grid excess: the stride must divide the grid");
  const SplineTrajectory Y = flat_outputs_of(setup, theta);
  const FlatOutputMap& flat = mp.flat;
  const double h = setup.duration_s / (points - 1);
  GridExcess out;
  out.stride = stride;
  const Eigen::Index visited = (points - 1) / stride + 1;
  out.excess.assign(static_cast<std::size_t>(visited), 0.0);
  Eigen::MatrixXd margins(stride == 1 ? visited : 0, flat.numMuscles());
  MusclePoint point;
  Jet q_jet(flat.numJoints(), 3), y_jet(flat.numFlatOutputs(), 3);
  for (int i = 0; i < points; i += stride) {
    const double t = h * i;
    const std::size_t at = static_cast<std::size_t>(i / stride);
    mp.path.jetInto(t, q_jet);
    Y.jetInto(t, y_jet);
    flat.inverseFromTorque(q_jet, jets[static_cast<std::size_t>(i)], y_jet, point);
    for (int j = 0; j < flat.numMuscles(); ++j) {
      if (margins.rows())
        margins(static_cast<Eigen::Index>(at), j) =
            signed_margin_excess(flat.model().muscle(j).getParameters(), point, j, a_min[j]);
      const double e = excess_of(point, j, a_min[j]);
      out.excess[at] = std::max(out.excess[at], e);
      note_worst(flat, point, j, t, e, out);
    }
  }
  if (margins.rows()) search_between_points(setup, mp, Y, a_min, margins, h, out);
  return out;
}

std::vector<double> violated_times(const GridExcess& g, double h, double tolerance) {
  std::vector<double> times;
  const std::size_t n = g.excess.size();
  for (std::size_t i = 0; i < n; ++i) {
    const double e = g.excess[i];
    if (!(e > tolerance)) continue;
    const bool left = i == 0 || e >= g.excess[i - 1], right = i + 1 == n || e >= g.excess[i + 1];
    if (left && right) times.push_back(h * static_cast<double>(g.stride) * static_cast<double>(i));
  }
  for (const auto& b : g.between)
    if (b.excess > tolerance) times.push_back(b.t_s);
  return times;
}

}  // namespace flatsos::planner::detail
