#include "flatsos/muscles/muscle_inverse.hpp"

#include <cmath>

#include "flatsos/muscles/hill_laws.hpp"

namespace flatsos::muscles {

namespace {
// Gradients are with respect to x = (F, dF, ddF).
using Grad = TendonForceJetGradient;
Grad operator*(double s, const Grad& g) { return {s * g[0], s * g[1], s * g[2]}; }
Grad operator+(const Grad& a, const Grad& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Grad operator-(const Grad& a, const Grad& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
}  // namespace

MuscleInverse invert_muscle(const MuscleParameters& p, const SecondOrderJet& force, const SecondOrderJet& path,
                            bool with_gradients) {
  MuscleInverse out;
  const double F = force.value, dF = force.rate, ddF = force.acceleration;
  if (!(F > 0.0)) {
    out.stage = MuscleInverse::Stage::SlackTendon;
    return out;
  }
  const double ls = tendon_length_from_force(p, F);
  const double d1 = tendon_force_derivative(p, ls);
  const double d2 = tendon_force_second_derivative(p, ls);
  const double dls = dF / d1;
  const double ddls = (ddF - d2 * dls * dls) / d1;
  const double u = dls - path.rate;
  const double du = ddls - path.acceleration;
  const double lc = path.value - ls;
  const double f = force_length(p, lc);
  const double f1 = force_length_derivative(p, lc);
  const double df = f1 * (-u);  // dL_C/dt = dL/dt - dL_S/dt = -u
  const double g = force_velocity(p, u);
  const double g1 = force_velocity_derivative(p, u);
  const double dg = g1 * du;
  out.tendon_length_m = ls;
  out.tendon_length_rate_m_per_s = dls;
  out.fiber_length_m = lc;
  out.shortening_velocity_m_per_s = u;
  out.force_ratio = g;
  if (!(g > 0.0)) {
    out.stage = MuscleInverse::Stage::NoForceCapacity;
    return out;
  }
  const double a = F / (p.max_isometric_force_N * f * g);
  const double r = dF / F - df / f - dg / g;
  const double da = a * r;
  out.activation = a;
  out.activation_rate_per_s = da;
  const ExcitationFromActivation n = excitation_from_activation(p, a, da);
  out.excitation = n.excitation;
  out.excitation_real = n.real_root;
  if (!with_gradients) return out;

  // The chain rule through every line above (Phi_S''' = 0: the tendon law is quadratic), once
  // for the tendon-force jet and once for the path's jet: the same lines, other seeds.
  const double f2 = force_length_second_derivative(p, lc);
  const double g2 = force_velocity_second_derivative(p, u);
  struct Seeds {
    Grad F, dF, ddF, L, dL, ddL;
  };
  auto chain = [&](const Seeds& x, Grad& a_x, Grad& da_x) {
    const Grad ls_x = (1.0 / d1) * x.F;
    const Grad d1_x = d2 * ls_x;
    const Grad dls_x = (1.0 / d1) * x.dF - (dls / d1) * d1_x;
    const Grad ddls_x = (1.0 / d1) * x.ddF - (2.0 * d2 * dls / d1) * dls_x - (ddls / d1) * d1_x;
    const Grad u_x = dls_x - x.dL, du_x = ddls_x - x.ddL, lc_x = x.L - ls_x;
    const Grad f_x = f1 * lc_x, f1_x = f2 * lc_x;
    const Grad g_x = g1 * u_x, g1_x = g2 * u_x;
    const Grad df_x = (-u) * f1_x - f1 * u_x;
    const Grad dg_x = du * g1_x + g1 * du_x;
    a_x = a * ((1.0 / F) * x.F - (1.0 / f) * f_x - (1.0 / g) * g_x);
    const Grad r_x = (1.0 / F) * x.dF - (dF / (F * F)) * x.F - (1.0 / f) * df_x + (df / (f * f)) * f_x -
                     (1.0 / g) * dg_x + (dg / (g * g)) * g_x;
    da_x = r * a_x + a * r_x;
  };
  const Grad zero{0.0, 0.0, 0.0}, e0{1.0, 0.0, 0.0}, e1{0.0, 1.0, 0.0}, e2{0.0, 0.0, 1.0};
  chain({e0, e1, e2, zero, zero, zero}, out.activation_gradient, out.activation_rate_gradient);
  chain({zero, zero, zero, e0, e1, e2}, out.path_activation_gradient, out.path_activation_rate_gradient);
  if (n.real_root) {
    // Q(n, a, da) = (1 - beta) n^2 + (beta - (1 - beta) a) n - beta a - T_act da = 0.
    const double beta = p.activation_beta();
    const double nn = n.excitation;
    const double Q_n = 2.0 * (1.0 - beta) * nn + beta - (1.0 - beta) * a;
    const double Q_a = -(1.0 - beta) * nn - beta;
    const double Q_da = -p.activation_time_constant_s;
    out.excitation_gradient = (-1.0 / Q_n) * (Q_a * out.activation_gradient + Q_da * out.activation_rate_gradient);
    out.path_excitation_gradient =
        (-1.0 / Q_n) * (Q_a * out.path_activation_gradient + Q_da * out.path_activation_rate_gradient);
  }
  return out;
}

}  // namespace flatsos::muscles
