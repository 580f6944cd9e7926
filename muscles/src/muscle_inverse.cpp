#include "flatsos/muscles/muscle_inverse.hpp"

#include <cmath>

#include "flatsos/muscles/muscle_model.hpp"

namespace flatsos::muscles {

namespace {

// A value with its gradient with respect to the K seeds (F, dF, ddF, L, dL, ddL) carried along
// in forward mode: the inverse's gradients follow every line of the inverse exactly, and with
// K = 0 (no gradients asked for) the same lines compute only values.
template <int K>
struct Dual {
  double v = 0.0;
  std::array<double, K> g{};
};
template <int K>
Dual<K> operator+(const Dual<K>& a, const Dual<K>& b) {
  Dual<K> r{a.v + b.v, {}};
  for (int i = 0; i < K; ++i) r.g[i] = a.g[i] + b.g[i];
  return r;
}
template <int K>
Dual<K> operator-(const Dual<K>& a, const Dual<K>& b) {
  Dual<K> r{a.v - b.v, {}};
  for (int i = 0; i < K; ++i) r.g[i] = a.g[i] - b.g[i];
  return r;
}
template <int K>
Dual<K> operator-(const Dual<K>& a) {
  Dual<K> r{-a.v, {}};
  for (int i = 0; i < K; ++i) r.g[i] = -a.g[i];
  return r;
}
template <int K>
Dual<K> operator*(const Dual<K>& a, const Dual<K>& b) {
  Dual<K> r{a.v * b.v, {}};
  for (int i = 0; i < K; ++i) r.g[i] = a.g[i] * b.v + a.v * b.g[i];
  return r;
}
template <int K>
Dual<K> operator*(double s, const Dual<K>& a) {
  Dual<K> r{s * a.v, {}};
  for (int i = 0; i < K; ++i) r.g[i] = s * a.g[i];
  return r;
}
template <int K>
Dual<K> operator/(const Dual<K>& a, const Dual<K>& b) {
  Dual<K> r{a.v / b.v, {}};
  for (int i = 0; i < K; ++i) r.g[i] = (a.g[i] - r.v * b.g[i]) / b.v;
  return r;
}
// phi(x) from phi(x.v) and phi'(x.v).
template <int K>
Dual<K> lift(double value, double slope, const Dual<K>& x) {
  Dual<K> r{value, {}};
  for (int i = 0; i < K; ++i) r.g[i] = slope * x.g[i];
  return r;
}
template <int K>
Dual<K> seed(double value, int index) {
  Dual<K> r{value, {}};
  if (index < K) r.g[index] = 1.0;
  return r;
}

template <int K>
void set_domain_distance(MuscleInverse& out, const Dual<K>& distance) {
  out.domain_distance = distance.v;
  if constexpr (K == 6)
    for (int i = 0; i < 3; ++i) {
      out.domain_distance_gradient[i] = distance.g[i];
      out.path_domain_distance_gradient[i] = distance.g[3 + i];
    }
}

template <int K>
MuscleInverse invert(const MuscleParameters& p, const SecondOrderJet& force, const SecondOrderJet& path) {
  using D = Dual<K>;
  MuscleInverse out;
  if (!(force.value > 0.0)) {
    out.stage = MuscleInverse::Stage::SlackTendon;
    out.domain_distance = -force.value / p.max_isometric_force_N;
    if constexpr (K > 0) out.domain_distance_gradient[0] = -1.0 / p.max_isometric_force_N;
    return out;
  }
  const D F = seed<K>(force.value, 0), dF = seed<K>(force.rate, 1), ddF = seed<K>(force.acceleration, 2);
  const D L = seed<K>(path.value, 3), dL = seed<K>(path.rate, 4), ddL = seed<K>(path.acceleration, 5);
  // Tendon: L_S = Phi_S^-1(F), dL_S = dF / Phi_S', ddL_S = (ddF - Phi_S'' dL_S^2) / Phi_S'.
  const MuscleModel& model = *p.model;
  const double ls_v = model.tendonLengthFromForce(p, F.v);
  const CurveJet tendon = model.tendonForce(p, ls_v);
  const D ls = lift(ls_v, 1.0 / tendon.slope, F);
  const D d1 = lift(tendon.slope, tendon.curvature, ls);
  const D d2 = lift(tendon.curvature, K > 0 ? model.tendonForceThirdDerivative(p, ls_v) : 0.0, ls);
  const D dls = dF / d1;
  const D ddls = (ddF - d2 * (dls * dls)) / d1;
  out.tendon_length_m = ls.v;
  out.tendon_length_rate_m_per_s = dls.v;
  // The muscle along the tendon, x = L - L_S, and the fibre: L_M = sqrt(x^2 + h^2),
  // cos = x / L_M, dL_M = cos dx, d cos = h^2 / L_M^3 dx.
  const D x = L - ls, dx = dL - dls, ddx = ddL - ddls;
  const double h = p.fiber_thickness_m();
  // A pennated fibre needs x > 0 (cos > 0). Without pennation the laws stay defined for any x,
  // as in the paper's model (the Gaussian force-length curve is positive everywhere).
  if (h != 0.0 && !(x.v > 0.0)) {
    out.stage = MuscleInverse::Stage::FiberCollapsed;
    out.fiber_length_m = x.v;
    set_domain_distance(out, (-1.0 / p.optimal_fiber_length_m) * x);
    return out;
  }
  D lm = x, c{1.0, {}}, dc{}, dlm = dx, ddlm = ddx;
  if (h != 0.0) {
    const double lm_v = std::hypot(x.v, h);
    lm = lift(lm_v, x.v / lm_v, x);
    c = x / lm;
    const D lm3 = lm * lm * lm;
    dc = (h * h) * (dx / lm3);
    dlm = c * dx;
    ddlm = dc * dx + c * ddx;
  }
  const D u = -dlm, du = -ddlm;  // shortening velocity along the fibre and its rate
  // Each law's jet comes with its curvature, which only the gradients (K = 6) use.
  const CurveJet fl = model.activeForceLength(p, lm.v);
  const D f = lift(fl.value, fl.slope, lm);
  const D f1 = lift(fl.slope, fl.curvature, lm);
  const D df = f1 * dlm;
  const CurveJet fv = model.forceVelocity(p, u.v);
  const D g = lift(fv.value, fv.slope, u);
  const D g1 = lift(fv.slope, fv.curvature, u);
  const D dg = g1 * du;
  out.fiber_length_m = lm.v;
  out.cos_pennation = c.v;
  out.shortening_velocity_m_per_s = u.v;
  out.force_ratio = g.v;
  if (!(g.v > 0.0)) {
    out.stage = MuscleInverse::Stage::NoForceCapacity;
    set_domain_distance(out, -g);
    return out;
  }
  // Active fibre force F / cos - Phi_P(L_M) = a Fmax f g, and its rate.
  const CurveJet pe = model.passiveFiberForce(p, lm.v);
  const D passive = lift(pe.value, pe.slope, lm);
  const D passive1 = lift(pe.slope, pe.curvature, lm);
  D active = F - passive, dactive = dF - passive1 * dlm;
  if (h != 0.0) {
    active = F / c - passive;
    dactive = dF / c - F * dc / (c * c) - passive1 * dlm;
  }
  const double fmax = p.max_isometric_force_N;
  const D capacity = fmax * (f * g);
  const D dcapacity = fmax * (df * g + f * dg);
  const D a = active / capacity;
  const D da = (dactive - a * dcapacity) / capacity;
  out.activation = a.v;
  out.activation_rate_per_s = da.v;
  const ExcitationFromActivation n = model.excitationFromActivation(p, a.v, da.v);
  out.excitation = n.excitation;
  out.excitation_real = n.real_root;
  if constexpr (K == 6) {
    for (int i = 0; i < 3; ++i) {
      out.activation_gradient[i] = a.g[i];
      out.activation_rate_gradient[i] = da.g[i];
      out.path_activation_gradient[i] = a.g[3 + i];
      out.path_activation_rate_gradient[i] = da.g[3 + i];
    }
    if (n.real_root)
      for (int i = 0; i < 3; ++i) {
        out.excitation_gradient[i] = n.d_activation * a.g[i] + n.d_activation_rate_s * da.g[i];
        out.path_excitation_gradient[i] = n.d_activation * a.g[3 + i] + n.d_activation_rate_s * da.g[3 + i];
      }
  }
  return out;
}

}  // namespace

MuscleInverse invert_muscle(const MuscleParameters& p, const SecondOrderJet& force, const SecondOrderJet& path,
                            bool with_gradients) {
  return with_gradients ? invert<6>(p, force, path) : invert<0>(p, force, path);
}

}  // namespace flatsos::muscles
