#include "path/path_effort.hpp"

#include <algorithm>
#include <boost/math/quadrature/gauss.hpp>
#include <cmath>
#include <utility>

#include "flatsos/muscles/muscle_inverse.hpp"
#include "sos/effort_exchange.hpp"

namespace flatsos::planner::detail {

namespace fm = flatsos::muscles;

namespace {

using Jet6 = Eigen::Matrix<double, 6, 1>;  // u = (F, dF, ddF, L, dL, ddL) of one muscle at a point

// One muscle's term l(F, a(u), n(u)) and its gradient in u. Where no excitation gives the
// activation's rate the inverse's closest excitation has no analytic gradient: central
// differences of it in u, as the effort's model takes them in theta (bounds/effort_model.cpp).
// False outside the muscle's domain or for a value that is not finite.
bool term_in_u(const fm::MuscleParameters& p, const Effort& effort, int j, const Jet6& u,
               bool gradient, MuscleEffortJet& term, Jet6& g) {
  const fm::SecondOrderJet F{u[0], u[1], u[2]}, L{u[3], u[4], u[5]};
  const fm::MuscleInverse inv = fm::invert_muscle(p, F, L, gradient);
  if (inv.stage != fm::MuscleInverse::Stage::Complete) return false;
  term = effort.muscleTerm(j, p, F.value, inv.activation, inv.excitation);
  if (!std::isfinite(term.value)) return false;
  if (!gradient) return true;
  Jet6 da, dn;
  for (std::size_t o = 0; o < 3; ++o) {
    da[static_cast<Eigen::Index>(o)] = inv.activation_gradient[o];
    da[static_cast<Eigen::Index>(o + 3)] = inv.path_activation_gradient[o];
    dn[static_cast<Eigen::Index>(o)] = inv.excitation_gradient[o];
    dn[static_cast<Eigen::Index>(o + 3)] = inv.path_excitation_gradient[o];
  }
  if (!inv.excitation_real)
    for (Eigen::Index i = 0; i < 6; ++i) {
      const double h = 1e-6 * (1.0 + std::abs(u[i]));
      Jet6 up = u, down = u;
      up[i] += h, down[i] -= h;
      const fm::MuscleInverse a =
          fm::invert_muscle(p, {up[0], up[1], up[2]}, {up[3], up[4], up[5]}, false);
      const fm::MuscleInverse b =
          fm::invert_muscle(p, {down[0], down[1], down[2]}, {down[3], down[4], down[5]}, false);
      const bool both = a.stage == fm::MuscleInverse::Stage::Complete &&
                        b.stage == fm::MuscleInverse::Stage::Complete;
      dn[i] = both ? (a.excitation - b.excitation) / (2.0 * h) : 0.0;
    }
  g = term.d_activation * da + term.d_excitation * dn;
  g[0] += term.d_force;
  return g.allFinite();
}

}  // namespace

PathEffort::PathEffort(const SosSetup& setup, const FlatOutputMap& flat,
                       const PathParameterization& P, const Effort& effort)
    : flat_(flat), effort_(effort), thetas_(setup.free_coefficients) {
  std::vector<double> ends = setup.basis.breakpoints();
  ends.insert(ends.end(), P.basis.breakpoints().begin(), P.basis.breakpoints().end());
  const EffortQuadrature q = effort_quadrature(std::move(ends));
  for (double t : q.times_s) points_.push_back(make_path_point(setup, flat, P, t));
  weights_s_ = q.weights_s;
}

std::vector<BoundPoint> PathEffort::boundPoints(const Eigen::VectorXd& c) const {
  return bound_points_along_path(flat_, points_, c);
}

std::vector<double> PathEffort::times_s() const {
  std::vector<double> out;
  for (const PathPoint& pt : points_) out.push_back(pt.flat.t_s);
  return out;
}

std::vector<int> PathEffort::localVariables(const PathPoint& pt) const {
  std::vector<int> out(pt.flat.columns.begin(), pt.flat.columns.end());
  for (int col : pt.path_columns) out.push_back(thetas_ + col);
  return out;
}

bool PathEffort::localTerms(std::size_t point, const Eigen::VectorXd& z, bool gradients,
                            std::vector<LocalTerm>& terms) const {
  const int n = flat_.numJoints(), m = flat_.numMuscles();
  const PathPoint& pt = points_[point];
  const Eigen::VectorXd theta = z.head(thetas_), c = z.tail(z.size() - thetas_);
  const Eigen::MatrixXd q = joint_jet(pt, c);
  Eigen::MatrixXd torque_gradient;  // row 3 r + k: d tau_r^(k) / d (joint jet)
  const Eigen::MatrixXd tau = gradients ? flat_.model().pinTree().torqueJet(q, torque_gradient)
                                        : flat_.model().pinTree().torqueJet(q);
  Eigen::MatrixXd F = pt.flat.base + flat_.Ctau() * tau;
  for (int k = 0; k < 3; ++k)
    for (std::size_t col = 0; col < pt.flat.columns.size(); ++col)
      F.col(k) += pt.flat.slope[static_cast<std::size_t>(k)].col(static_cast<Eigen::Index>(col)) *
                  theta[pt.flat.columns[col]];
  const auto thetas = static_cast<Eigen::Index>(pt.flat.columns.size());
  const auto paths = static_cast<Eigen::Index>(pt.path_columns.size());
  Eigen::MatrixXd dq, dtau, path_gradient(3, kPathOrders * n);
  if (gradients) {
    dq = joint_jet_slope(pt, n);
    dtau = torque_gradient * dq;  // row 3 r + k
  }
  terms.resize(static_cast<std::size_t>(m));
  for (int j = 0; j < m; ++j) {
    const fm::MuscleParameters& p = flat_.model().muscle(j).getParameters();
    const fm::SecondOrderJet L = flat_.pathLengthJet(j, q);
    LocalTerm& t = terms[static_cast<std::size_t>(j)];
    t.u << F(j, 0), F(j, 1), F(j, 2), L.value, L.rate, L.acceleration;
    if (!term_in_u(p, effort_, j, t.u, gradients, t.jet, t.gradient_u)) return false;
    if (!gradients) continue;
    // d u / d (theta, c) over the point's local variables: F through the flat outputs and the
    // torque jet, L through the joint jet.
    t.Ju = Eigen::MatrixXd::Zero(6, thetas + paths);
    for (int o = 0; o < 3; ++o)
      t.Ju.row(o).head(thetas) = pt.flat.slope[static_cast<std::size_t>(o)].row(j);
    for (int o = 0; o < 3; ++o)
      for (int r = 0; r < n; ++r)
        t.Ju.row(o).tail(paths) += flat_.Ctau()(j, r) * dtau.row(3 * r + o);
    flat_.pathLengthJetGradient(j, q, path_gradient);
    t.Ju.bottomRightCorner(3, paths) = path_gradient * dq;
  }
  return true;
}

bool PathEffort::value(const Eigen::VectorXd& z, double& E) const {
  std::vector<LocalTerm> terms;
  E = 0.0;
  for (std::size_t k = 0; k < points_.size(); ++k) {
    if (!localTerms(k, z, false, terms)) return false;
    for (const LocalTerm& t : terms) E += weights_s_[k] * t.jet.value;
  }
  return std::isfinite(E);
}

bool PathEffort::gradient(const Eigen::VectorXd& z, Eigen::VectorXd& g) const {
  std::vector<LocalTerm> terms;
  g = Eigen::VectorXd::Zero(z.size());
  for (std::size_t k = 0; k < points_.size(); ++k) {
    if (!localTerms(k, z, true, terms)) return false;
    const std::vector<int> variables = localVariables(points_[k]);
    for (const LocalTerm& t : terms) {
      const Eigen::VectorXd local = t.Ju.transpose() * t.gradient_u;
      for (std::size_t i = 0; i < variables.size(); ++i)
        g[variables[i]] += weights_s_[k] * local[static_cast<Eigen::Index>(i)];
    }
  }
  return g.allFinite();
}

}  // namespace flatsos::planner::detail
