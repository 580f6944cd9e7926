#include "flatsos/muscles/muscle_inverse.hpp"

#include <algorithm>
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

// K = 3 seeds only the force's jet (the path's gradients stay 0), K = 6 both.
template <int K>
void set_domain_distance(MuscleInverse& out, const Dual<K>& distance) {
  out.domain_distance = distance.v;
  if constexpr (K >= 3)
    for (int i = 0; i < 3; ++i) out.domain_distance_gradient[i] = distance.g[i];
  if constexpr (K == 6)
    for (int i = 0; i < 3; ++i) out.path_domain_distance_gradient[i] = distance.g[3 + i];
}

// The activation of a model whose maximum velocity scales with activation: a from
//   h(a) = a g(u / k(a)) - R = 0,   R = (F / cos - Phi_P - D(u)) / (Fmax f),
// where k is taken at a clamped to [floor, 1] as the forward model does. h increases with a
// wherever g > 0 (g(w) - w g'(w) >= 1 for Thelen's concave eccentric branch, and a g grows on
// the concentric one), so the root is found by bisection kept tight by Newton steps. The gradient
// and the rate follow by implicit differentiation:
//   (g - a g' u k' / k^2) da = dR - (a g' / k) du.
template <int K>
struct ScaledActivation {
  bool has_capacity = true;
  Dual<K> domain_distance;  // -g at full activation (or at the floor, for R <= 0), when !has_capacity
  double force_ratio = 0.0;  // g(u / k(a))
  Dual<K> activation, activation_rate;
};

template <int K>
ScaledActivation<K> activation_with_velocity_scale(const MuscleParameters& p, const Dual<K>& u, const Dual<K>& du,
                                                   const Dual<K>& ratio, const Dual<K>& ratio_rate) {
  using D = Dual<K>;
  const MuscleModel& model = *p.model;
  const auto clamped = [&](double a) { return std::clamp(a, p.activation_floor, 1.0); };
  const auto scale = [&](double a) {
    CurveJet k = model.maxVelocityScale(p, clamped(a));
    if (!(a > p.activation_floor && a < 1.0)) k.slope = k.curvature = 0.0;
    return k;
  };
  ScaledActivation<K> out;
  // Capacity: some activation of the sign R asks for must give g > 0.
  const double a_edge = ratio.v > 0.0 ? 1.0 : p.activation_floor;
  const CurveJet g_edge = model.forceVelocity(p, u.v / model.maxVelocityScale(p, a_edge).value);
  if (!(g_edge.value > 0.0)) {
    out.has_capacity = false;
    out.force_ratio = g_edge.value;
    out.domain_distance = lift(-g_edge.value, -g_edge.slope / model.maxVelocityScale(p, a_edge).value, u);
    return out;
  }
  const auto h = [&](double a) { return a * model.forceVelocity(p, u.v / scale(a).value).value - ratio.v; };
  double lo = 0.0, hi = 1.0;
  if (ratio.v > 0.0) {
    while (h(hi) < 0.0) hi *= 2.0;
  } else {
    lo = ratio.v / g_edge.value - 1.0, hi = p.activation_floor;  // linear below the floor
  }
  double a = 0.5 * (lo + hi);
  for (int iteration = 0; iteration < 200 && hi - lo > 1e-16 * (1.0 + std::abs(a)); ++iteration) {
    const CurveJet k = scale(a);
    const double w = u.v / k.value;
    const CurveJet g = model.forceVelocity(p, w);
    const double value = a * g.value - ratio.v;
    if (value == 0.0) break;
    (value < 0.0 ? lo : hi) = a;
    const double slope = g.value - a * g.slope * w * k.slope / k.value;
    const double newton = slope > 0.0 ? a - value / slope : lo - 1.0;
    a = newton > lo && newton < hi ? newton : 0.5 * (lo + hi);
  }
  const CurveJet k = scale(a);
  const double w = u.v / k.value;
  const CurveJet g = model.forceVelocity(p, w);
  const double jacobian = g.value - a * g.slope * w * k.slope / k.value;
  D a_dual = (1.0 / jacobian) * (ratio - (a * g.slope / k.value) * u);
  a_dual.v = a;
  const D k_dual = lift(k.value, k.slope, a_dual), k1 = lift(k.slope, k.curvature, a_dual);
  const D w_dual = u / k_dual;
  const D g_dual = lift(g.value, g.slope, w_dual), g1 = lift(g.slope, g.curvature, w_dual);
  out.force_ratio = g.value;
  out.activation = a_dual;
  out.activation_rate = (ratio_rate - a_dual * g1 * du / k_dual) / (g_dual - a_dual * g1 * w_dual * k1 / k_dual);
  return out;
}

// The fibre from the muscle along the tendon x: L_M = sqrt(x^2 + h^2), cos = x / L_M,
// dL_M = cos dx, d cos = h^2 / L_M^3 dx (h = 0: L_M = x, cos = 1).
template <int K>
struct FiberJets {
  Dual<K> length, cos{1.0, {}}, cos_rate, length_rate, length_acceleration;
};
template <int K>
FiberJets<K> fiber_jets(double h, const Dual<K>& x, const Dual<K>& dx, const Dual<K>& ddx) {
  FiberJets<K> out{x, {1.0, {}}, {}, dx, ddx};
  if (h == 0.0) return out;
  const double lm_v = std::hypot(x.v, h);
  out.length = lift(lm_v, x.v / lm_v, x);
  out.cos = x / out.length;
  out.cos_rate = (h * h) * (dx / (out.length * out.length * out.length));
  out.length_rate = out.cos * dx;
  out.length_acceleration = out.cos_rate * dx + out.cos * ddx;
  return out;
}

// The gradients of a, da/dt and n with respect to the force's jet, and with K = 6 the path's.
template <int K>
void store_gradients(MuscleInverse& out, const Dual<K>& a, const Dual<K>& da, const ExcitationFromActivation& n) {
  for (int i = 0; i < K; ++i) {
    auto& activation = i < 3 ? out.activation_gradient : out.path_activation_gradient;
    auto& rate = i < 3 ? out.activation_rate_gradient : out.path_activation_rate_gradient;
    auto& excitation = i < 3 ? out.excitation_gradient : out.path_excitation_gradient;
    const auto o = static_cast<std::size_t>(i % 3);
    activation[o] = a.g[i];
    rate[o] = da.g[i];
    if (n.real_root) excitation[o] = n.d_activation * a.g[i] + n.d_activation_rate_s * da.g[i];
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
  const FiberJets<K> fiber = fiber_jets(h, x, dx, ddx);
  const D &lm = fiber.length, &c = fiber.cos, &dc = fiber.cos_rate, &dlm = fiber.length_rate;
  const D& ddlm = fiber.length_acceleration;
  const D u = -dlm, du = -ddlm;  // shortening velocity along the fibre and its rate
  // Each law's jet comes with its curvature, which only the gradients (K = 6) use.
  const CurveJet fl = model.activeForceLength(p, lm.v);
  const D f = lift(fl.value, fl.slope, lm);
  const D f1 = lift(fl.slope, fl.curvature, lm);
  const D df = f1 * dlm;
  out.fiber_length_m = lm.v;
  out.cos_pennation = c.v;
  out.shortening_velocity_m_per_s = u.v;
  // Active fibre force F / cos - Phi_P(L_M) - D(u) = a Fmax f g(u / k(a)), and its rate
  // (D(u) = -b u the fibre's damping).
  const CurveJet pe = model.passiveFiberForce(p, lm.v);
  const D passive = lift(pe.value, pe.slope, lm);
  const D passive1 = lift(pe.slope, pe.curvature, lm);
  D active = F - passive, dactive = dF - passive1 * dlm;
  if (h != 0.0) {
    active = F / c - passive;
    dactive = dF / c - F * dc / (c * c) - passive1 * dlm;
  }
  const double fmax = p.max_isometric_force_N;
  if (p.fiber_damping != 0.0) {
    const double b = p.fiber_damping * fmax / p.max_shortening_velocity_m_per_s();
    active = active + b * u;
    dactive = dactive + b * du;
  }
  D a, da;
  if (model.scalesMaxVelocityWithActivation()) {
    const D capacity = fmax * f, dcapacity = fmax * df;
    const D ratio = active / capacity;
    const ScaledActivation<K> s = activation_with_velocity_scale(p, u, du, ratio, (dactive - ratio * dcapacity) / capacity);
    out.force_ratio = s.force_ratio;
    if (!s.has_capacity) {
      out.stage = MuscleInverse::Stage::NoForceCapacity;
      set_domain_distance(out, s.domain_distance);
      return out;
    }
    a = s.activation, da = s.activation_rate;
  } else {
    const CurveJet fv = model.forceVelocity(p, u.v);
    const D g = lift(fv.value, fv.slope, u);
    out.force_ratio = g.v;
    if (!(g.v > 0.0)) {
      out.stage = MuscleInverse::Stage::NoForceCapacity;
      set_domain_distance(out, -g);
      return out;
    }
    const D dg = lift(fv.slope, fv.curvature, u) * du;
    const D capacity = fmax * (f * g), dcapacity = fmax * (df * g + f * dg);
    a = active / capacity;
    da = (dactive - a * dcapacity) / capacity;
  }
  out.activation = a.v;
  out.activation_rate_per_s = da.v;
  const ExcitationFromActivation n = model.excitationFromActivation(p, a.v, da.v);
  out.excitation = n.excitation;
  out.excitation_real = n.real_root;
  if constexpr (K > 0) store_gradients(out, a, da, n);
  return out;
}

}  // namespace

MuscleInverse invert_muscle(const MuscleParameters& p, const SecondOrderJet& force, const SecondOrderJet& path,
                            bool with_gradients) {
  return invert_muscle(p, force, path, with_gradients ? InverseGradients::ForceAndPathJets : InverseGradients::None);
}

MuscleInverse invert_muscle(const MuscleParameters& p, const SecondOrderJet& force, const SecondOrderJet& path,
                            InverseGradients gradients) {
  switch (gradients) {
    case InverseGradients::None: return invert<0>(p, force, path);
    case InverseGradients::ForceJet: return invert<3>(p, force, path);
    case InverseGradients::ForceAndPathJets: break;
  }
  return invert<6>(p, force, path);
}

}  // namespace flatsos::muscles
