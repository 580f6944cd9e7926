#include "bounds/effort_model.hpp"

#include <algorithm>
#include <cmath>

#include "flatsos/muscles/muscle_inverse.hpp"

namespace flatsos::planner::detail {

namespace fm = flatsos::muscles;

namespace {

fm::SecondOrderJet force_jet(const BoundPoint& bp, int j, const Eigen::VectorXd& theta) {
  double F[3];
  for (std::size_t k = 0; k < 3; ++k) {
    double v = bp.base(j, static_cast<Eigen::Index>(k));
    for (std::size_t c = 0; c < bp.columns.size(); ++c) v += bp.slope[k](j, static_cast<Eigen::Index>(c)) * theta[bp.columns[c]];
    F[k] = v;
  }
  return {F[0], F[1], F[2]};
}

// Where no excitation gives the activation's rate, the inverse's closest excitation has no
// analytic gradient: central differences in the force's jet, so that the effort's model stays
// consistent with its values (with a zero gradient there, steps the model promised lowered
// nothing and the sequential QP stalled).
fm::TendonForceJetGradient closest_excitation_gradient(const fm::MuscleParameters& p, const fm::SecondOrderJet& F,
                                                       const fm::SecondOrderJet& path) {
  fm::TendonForceJetGradient g{};
  const double scale[3] = {1.0 + std::abs(F.value), 1.0 + std::abs(F.rate), 1.0 + std::abs(F.acceleration)};
  for (int k = 0; k < 3; ++k) {
    const double h = 1e-6 * scale[k];
    fm::SecondOrderJet plus = F, minus = F;
    double* up[3] = {&plus.value, &plus.rate, &plus.acceleration};
    double* down[3] = {&minus.value, &minus.rate, &minus.acceleration};
    *up[k] += h, *down[k] -= h;
    const fm::MuscleInverse a = fm::invert_muscle(p, plus, path, false), b = fm::invert_muscle(p, minus, path, false);
    if (a.stage == fm::MuscleInverse::Stage::Complete && b.stage == fm::MuscleInverse::Stage::Complete)
      g[static_cast<std::size_t>(k)] = (a.excitation - b.excitation) / (2.0 * h);
  }
  return g;
}

// Adds w (l_F g_F + l_a g_a + l_n g_n) to the gradient and w (l_FF g_F g_F^T + ...) to the
// Hessian, over the point's columns only.
void add_derivatives(const BoundPoint& bp, int j, const fm::MuscleInverse& inv, const MuscleEffortJet& term, double w,
                     Eigen::VectorXd& g_force, Eigen::VectorXd& g_activation, Eigen::VectorXd& g_excitation,
                     EffortModel& out) {
  const auto k = static_cast<Eigen::Index>(bp.columns.size());
  g_force.resize(k), g_activation.resize(k), g_excitation.resize(k);
  for (Eigen::Index c = 0; c < k; ++c) {
    g_force[c] = bp.slope[0](j, c);
    g_activation[c] = column_derivative(bp, inv.activation_gradient, j, static_cast<std::size_t>(c));
    g_excitation[c] = column_derivative(bp, inv.excitation_gradient, j, static_cast<std::size_t>(c));
  }
  for (Eigen::Index a = 0; a < k; ++a) {
    const int ca = bp.columns[static_cast<std::size_t>(a)];
    out.gradient[ca] += w * (term.d_force * g_force[a] + term.d_activation * g_activation[a] +
                             term.d_excitation * g_excitation[a]);
    const double hf = w * term.d_force2 * g_force[a], ha = w * term.d_activation2 * g_activation[a],
                 hn = w * term.d_excitation2 * g_excitation[a];
    for (Eigen::Index b = 0; b < k; ++b)
      out.hessian(ca, bp.columns[static_cast<std::size_t>(b)]) +=
          hf * g_force[b] + ha * g_activation[b] + hn * g_excitation[b];
  }
}

}  // namespace

bool evaluate_effort(const FlatOutputMap& flat, const Effort& effort, const std::vector<BoundPoint>& points,
                     const std::vector<double>& weights_s, const Eigen::VectorXd& theta, bool derivatives,
                     EffortModel& out, bool closest_excitation) {
  const int m = flat.numMuscles();
  const Eigen::Index n = theta.size();
  out.value = 0.0;
  if (derivatives) out.gradient.setZero(n), out.hessian.setZero(n, n);
  Eigen::VectorXd g_force, g_activation, g_excitation;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const BoundPoint& bp = points[i];
    for (int j = 0; j < m; ++j) {
      const fm::MuscleParameters& params = flat.model().muscle(j).getParameters();
      const fm::SecondOrderJet F = force_jet(bp, j, theta);
      fm::MuscleInverse inv = fm::invert_muscle(params, F, bp.path[static_cast<std::size_t>(j)], derivatives);
      if (inv.stage != fm::MuscleInverse::Stage::Complete || (!inv.excitation_real && !closest_excitation)) return false;
      if (derivatives && !inv.excitation_real)
        inv.excitation_gradient = closest_excitation_gradient(params, F, bp.path[static_cast<std::size_t>(j)]);
      const MuscleEffortJet term = effort.muscleTerm(j, params, F.value, inv.activation, inv.excitation);
      if (!std::isfinite(term.value)) return false;
      out.value += weights_s[i] * term.value;
      if (derivatives) add_derivatives(bp, j, inv, term, weights_s[i], g_force, g_activation, g_excitation, out);
    }
  }
  return std::isfinite(out.value) && (!derivatives || (out.gradient.allFinite() && out.hessian.allFinite()));
}

void place_linearized_bound_rows(const BoundRowsAt& at, Eigen::MatrixXd& J, Eigen::VectorXd& lower) {
  for (const Eigen::Triplet<double>& e : at.jacobian) J(e.row(), e.col()) += e.value();
  for (std::size_t i = 0; i < at.value.size(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    lower[r] = -at.value[i];
    if (J.row(r).cwiseAbs().maxCoeff() <= 1e-12) lower[r] = std::min(lower[r], 0.0);
  }
}

}  // namespace flatsos::planner::detail
