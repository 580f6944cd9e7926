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

// z = (F / cos - Phi_P(L_M)) / (max(a, floor) Fmax f(L_M)) and what its partials need.
struct ForceRatioParts {
  FiberGeometry geometry;
  double cos_pennation = 1.0;  // floored
  bool cos_floored = false;
  CurveJet f;                  // value floored
  bool f_floored = false;
  CurveJet passive;
  double denominator = 1.0;    // a_eff Fmax f
  double z = 0.0;
};
ForceRatioParts force_ratio_parts(const MuscleParameters& p, double tendon_force_N, double activation,
                                  double along_tendon_m) {
  ForceRatioParts r;
  r.geometry = fiber_geometry(p, along_tendon_m);
  r.cos_floored = r.geometry.cos_pennation < kMinCosPennation;
  r.cos_pennation = r.cos_floored ? kMinCosPennation : r.geometry.cos_pennation;
  r.f = p.model->activeForceLength(p, r.geometry.length_m);
  r.f_floored = !(r.f.value >= kForceLengthFloor);
  if (r.f_floored) r.f.value = kForceLengthFloor;
  r.passive = p.model->passiveFiberForce(p, r.geometry.length_m);
  r.denominator = effective_activation(p, activation) * p.max_isometric_force_N * r.f.value;
  r.z = (tendon_force_N / r.cos_pennation - r.passive.value) / r.denominator;
  return r;
}
}  // namespace

double effective_activation(const MuscleParameters& p, double activation) {
  return std::max(activation, p.activation_floor);
}

double force_ratio(const MuscleParameters& p, double tendon_force_N, double activation, double along_tendon_m) {
  return force_ratio_parts(p, tendon_force_N, activation, along_tendon_m).z;
}

double fiber_shortening_velocity(const MuscleParameters& p, double tendon_force_N, double activation,
                                 double along_tendon_m) {
  return fiber_velocity_from_force_ratio(p, force_ratio(p, tendon_force_N, activation, along_tendon_m));
}

double tendon_length_derivative(const MuscleParameters& p, double tendon_length_m, double activation,
                                double musculotendon_length_m, double musculotendon_lengthening_rate_m_per_s) {
  const ForceRatioParts r =
      force_ratio_parts(p, tendon_force(p, tendon_length_m), activation, musculotendon_length_m - tendon_length_m);
  // The fibre shortens at u along itself, so the muscle along the tendon, x = L - L_S, shortens
  // at u / cos: dL_S/dt = dL/dt + u / cos.
  return fiber_velocity_from_force_ratio(p, r.z) / r.cos_pennation + musculotendon_lengthening_rate_m_per_s;
}

TendonLengthDerivativePartials tendon_length_derivative_partials(const MuscleParameters& p, double tendon_length_m,
                                                                 double activation, double musculotendon_length_m) {
  // dL_S/dt = w + dL/dt, w = g^-1(z) / cos(x), x = L - L_S, z as in force_ratio_parts.
  const CurveJet tendon = p.model->tendonForce(p, tendon_length_m);
  const ForceRatioParts r = force_ratio_parts(p, tendon.value, activation, musculotendon_length_m - tendon_length_m);
  const double c = r.cos_pennation;
  const double dc_dx = r.cos_floored ? 0.0 : r.geometry.cos_pennation_d_along;
  const double dlength_dx = r.geometry.length_d_along;
  const double df_dx = r.f_floored ? 0.0 : r.f.slope * dlength_dx;
  const double dpassive_dx = r.passive.slope * dlength_dx;
  const double dz_dx = (-tendon.value * dc_dx / (c * c) - dpassive_dx) / r.denominator - r.z * df_dx / r.f.value;
  const double dz_dtendon_direct = tendon.slope / (c * r.denominator);
  const double a_eff = effective_activation(p, activation);
  const double dz_dactivation = activation > p.activation_floor ? -r.z / a_eff : 0.0;
  const CurveJet velocity = p.model->fiberVelocityFromForceRatio(p, r.z);
  const double du_dz = velocity.slope;
  double dw_dx = du_dz * dz_dx / c;
  if (dc_dx != 0.0) dw_dx -= velocity.value * dc_dx / (c * c);
  // dx/dL_S = -1, dx/dL = 1.
  return {du_dz * dz_dtendon_direct / c - dw_dx, du_dz * dz_dactivation / c, dw_dx};
}

}  // namespace flatsos::muscles
