#include "flatsos/muscles/hill_laws.hpp"

#include <algorithm>
#include <cmath>

// The laws every model shares (pennation, the contraction dynamics built on a model's curves);
// each model's own curves are in its file (richter_warner_muscle.cpp, ...).

namespace flatsos::muscles {
namespace {
// Floor on f(L_C) in the force ratio: only reached for fiber lengths many widths from Lopt.
constexpr double kForceLengthFloor = 1e-12;
}  // namespace

// ---------------------------------------------------------------- pennation
FiberGeometry fiber_geometry(const MuscleParameters& p, double along_tendon_m) {
  FiberGeometry g;
  const double h = p.fiber_thickness_m();
  if (h == 0.0) {  // fibres along the tendon: exactly the unpennated model
    g.length_m = along_tendon_m;
    g.cos_pennation = 1.0;
    g.length_d_along = 1.0;
    return g;
  }
  g.length_m = std::hypot(along_tendon_m, h);
  g.cos_pennation = along_tendon_m / g.length_m;
  g.length_d_along = g.cos_pennation;
  g.cos_pennation_d_along = h * h / (g.length_m * g.length_m * g.length_m);
  return g;
}

// ---------------------------------------------------------------- contraction dynamics
namespace {
// Smallest cos(pennation) the forward model divides by (pennation up to 89.4 degrees): a fibre
// squeezed to its thickness holds no tendon force, and this keeps the model finite there.
constexpr double kMinCosPennation = 1e-2;

// The force balance along the fibre, a Fmax f g(u / k) + D(u) = F / cos - Phi_P =: A, solved for
// the shortening velocity as u = k V(z), V the model's inverse of g and z the force ratio: without
// damping z = A / (a Fmax f); with it (D(u) = -b u, b = beta Fmax / Vmax) z is the root of
//   Phi(z) = a Fmax f z - b k V(z) - A,
// strictly increasing (V decreases), found by a safeguarded Newton iteration.
struct ForceBalance {
  FiberGeometry geometry;
  double cos_pennation = 1.0;  // floored
  bool cos_floored = false;
  CurveJet f;                  // value floored
  bool f_floored = false;
  CurveJet passive;
  double denominator = 1.0;    // a_eff Fmax f
  double damping = 0.0;        // b, N s/m
  CurveJet scale{1.0, 0.0, 0.0};  // k(a_eff)
  double z = 0.0;
  CurveJet velocity;           // V(z) and V'(z), per unit k
  double phi_z = 1.0;          // dPhi/dz
  bool fiber_held = false;     // at or below the model's minimum fibre length (u = 0)
  bool own_law = false;        // the model's own velocity law gave `own` (MuscleModel::hasOwnVelocityLaw)
  OwnFiberVelocity own;
  double shortening_velocity() const {
    if (own_law) return own.shortening_m_per_s;
    return fiber_held ? 0.0 : scale.value * velocity.value;
  }
};

double solve_damped_force_ratio(const MuscleParameters& p, const ForceBalance& r, double numerator_N) {
  const auto phi = [&](double z) {
    return r.denominator * z - r.damping * r.scale.value * p.model->fiberVelocityFromForceRatio(p, z).value - numerator_N;
  };
  double z = numerator_N / r.denominator;
  // Bracket the root by steps that double, then Newton kept inside the bracket (bisection when it
  // would leave it).
  double lo = z, hi = z, step = 0.1 + std::abs(z);
  if (phi(z) < 0.0) {
    while (phi(hi) < 0.0) lo = hi, hi += step, step *= 2.0;
  } else {
    while (phi(lo) > 0.0) hi = lo, lo -= step, step *= 2.0;
  }
  z = 0.5 * (lo + hi);
  for (int iteration = 0; iteration < 100 && hi - lo > 1e-15 * (1.0 + std::abs(z)); ++iteration) {
    const CurveJet v = p.model->fiberVelocityFromForceRatio(p, z);
    const double value = r.denominator * z - r.damping * r.scale.value * v.value - numerator_N;
    if (value == 0.0) return z;
    (value < 0.0 ? lo : hi) = z;
    const double newton = z - value / (r.denominator - r.damping * r.scale.value * v.slope);
    // A step below the tolerance has converged (it may land on z itself, which is not inside
    // the bracket and would otherwise restart bisection from the far end).
    if (std::abs(newton - z) <= 1e-15 * (1.0 + std::abs(z))) return newton;
    z = newton > lo && newton < hi ? newton : 0.5 * (lo + hi);
  }
  return z;
}

ForceBalance force_balance(const MuscleParameters& p, double tendon_force_N, double activation, double along_tendon_m) {
  ForceBalance r;
  r.geometry = fiber_geometry(p, along_tendon_m);
  r.cos_floored = r.geometry.cos_pennation < kMinCosPennation;
  r.cos_pennation = r.cos_floored ? kMinCosPennation : r.geometry.cos_pennation;
  r.f = p.model->activeForceLength(p, r.geometry.length_m);
  r.f_floored = !(r.f.value >= kForceLengthFloor);
  if (r.f_floored) r.f.value = kForceLengthFloor;
  r.passive = p.model->passiveFiberForce(p, r.geometry.length_m);
  const double a_eff = effective_activation(p, activation);
  r.denominator = a_eff * p.max_isometric_force_N * r.f.value;
  if (p.model->scalesMaxVelocityWithActivation()) r.scale = p.model->maxVelocityScale(p, a_eff);
  r.damping = p.fiber_damping * p.max_isometric_force_N / p.max_shortening_velocity_m_per_s();
  const double numerator_N = tendon_force_N / r.cos_pennation - r.passive.value;
  if (p.model->hasOwnVelocityLaw()) {
    r.own_law = true;
    r.own = p.model->ownFiberVelocity(p, activation, r.geometry.length_m, numerator_N);
    return r;
  }
  r.z = r.damping == 0.0 ? numerator_N / r.denominator : solve_damped_force_ratio(p, r, numerator_N);
  r.velocity = p.model->fiberVelocityFromForceRatio(p, r.z);
  r.phi_z = r.denominator - r.damping * r.scale.value * r.velocity.slope;
  // OpenSim's Millard clamp: a fibre below its minimum length, or at it and shortening, holds.
  const double minimum_m = p.model->minimumFiberLength(p);
  if (minimum_m > 0.0) {
    const double length = r.geometry.length_m;
    r.fiber_held = length < minimum_m || (length <= minimum_m && r.scale.value * r.velocity.value >= 0.0);
  }
  return r;
}
// dL_S/dt = u / cos(x) + dL/dt with u = U(A, a, L_M) the model's own law, A = F(L_S) / cos(x) -
// Phi_P(L_M(x)), x = L - L_S.
TendonLengthDerivativePartials own_law_partials(const ForceBalance& r, const CurveJet& tendon) {
  const double c = r.cos_pennation, u = r.own.shortening_m_per_s;
  const double dc_dx = r.cos_floored ? 0.0 : r.geometry.cos_pennation_d_along;
  const double dlength_dx = r.geometry.length_d_along;
  const double dA_dx = -tendon.value * dc_dx / (c * c) - r.passive.slope * dlength_dx;
  const double du_dx = r.own.d_fiber_force * dA_dx + r.own.d_fiber_length * dlength_dx;
  const double dw_dx = du_dx / c - u * dc_dx / (c * c);
  const double du_dtendon_direct = r.own.d_fiber_force * tendon.slope / c;
  return {du_dtendon_direct / c - dw_dx, r.own.d_activation / c, dw_dx};
}
}  // namespace

double effective_activation(const MuscleParameters& p, double activation) {
  return std::max(activation, p.activation_floor);
}

double force_ratio(const MuscleParameters& p, double tendon_force_N, double activation, double along_tendon_m) {
  return force_balance(p, tendon_force_N, activation, along_tendon_m).z;
}

double fiber_shortening_velocity(const MuscleParameters& p, double tendon_force_N, double activation,
                                 double along_tendon_m) {
  return force_balance(p, tendon_force_N, activation, along_tendon_m).shortening_velocity();
}

double tendon_length_derivative(const MuscleParameters& p, double tendon_length_m, double activation,
                                double musculotendon_length_m, double musculotendon_lengthening_rate_m_per_s) {
  const ForceBalance r =
      force_balance(p, tendon_force(p, tendon_length_m), activation, musculotendon_length_m - tendon_length_m);
  // The fibre shortens at u along itself, so the muscle along the tendon, x = L - L_S, shortens
  // at u / cos: dL_S/dt = dL/dt + u / cos.
  return r.shortening_velocity() / r.cos_pennation + musculotendon_lengthening_rate_m_per_s;
}

TendonLengthDerivativePartials tendon_length_derivative_partials(const MuscleParameters& p, double tendon_length_m,
                                                                 double activation, double musculotendon_length_m) {
  // dL_S/dt = w + dL/dt, w = u / cos(x), u = k V(z), x = L - L_S, z the root of
  // Phi = den z - b k V(z) - (F / cos - Phi_P) (force_balance): dz = -dPhi / Phi_z.
  const CurveJet tendon = p.model->tendonForce(p, tendon_length_m);
  const ForceBalance r = force_balance(p, tendon.value, activation, musculotendon_length_m - tendon_length_m);
  if (r.own_law) return own_law_partials(r, tendon);
  if (r.fiber_held) return {};  // dL_S/dt = dL/dt: only the path moves it
  const double c = r.cos_pennation, k = r.scale.value, u = r.shortening_velocity();
  const double dc_dx = r.cos_floored ? 0.0 : r.geometry.cos_pennation_d_along;
  const double dlength_dx = r.geometry.length_d_along;
  const double dden_dx = r.f_floored ? 0.0 : r.denominator * r.f.slope * dlength_dx / r.f.value;
  const double dnumerator_dx = -tendon.value * dc_dx / (c * c) - r.passive.slope * dlength_dx;
  const double dz_dx = -(dden_dx * r.z - dnumerator_dx) / r.phi_z;
  const double dz_dtendon_direct = tendon.slope / (c * r.phi_z);
  const double a_eff = effective_activation(p, activation);
  const bool above_floor = activation > p.activation_floor;
  const double dk_da = above_floor ? r.scale.slope : 0.0;
  const double dphi_da = (above_floor ? r.denominator / a_eff * r.z : 0.0) - r.damping * dk_da * r.velocity.value;
  const double dz_da = -dphi_da / r.phi_z;
  const double du_dz = k * r.velocity.slope;
  double dw_dx = du_dz * dz_dx / c;
  if (dc_dx != 0.0) dw_dx -= u * dc_dx / (c * c);
  const double du_da = du_dz * dz_da + dk_da * r.velocity.value;
  // dx/dL_S = -1, dx/dL = 1.
  return {du_dz * dz_dtendon_direct / c - dw_dx, du_da / c, dw_dx};
}

}  // namespace flatsos::muscles
