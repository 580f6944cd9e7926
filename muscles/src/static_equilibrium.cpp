#include "flatsos/muscles/static_equilibrium.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "flatsos/muscles/hill_laws.hpp"

namespace flatsos::muscles {

double static_equilibrium_tendon_length(const MuscleParameters& p, double length_m,
                                        double activation) {
  const std::string who = "muscle '" + p.name + "': static equilibrium: ";
  if (!(activation >= 0.0 && activation <= 1.0))
    throw std::domain_error(who + "activation " + std::to_string(activation) + " is outside [0, 1]");
  if (!std::isfinite(length_m)) throw std::domain_error(who + "musculotendon length is not finite");
  const double room = length_m - p.tendon_slack_length_m;  // fiber length with a slack tendon
  if (!(room > 0.0))
    throw std::domain_error(who + "none exists: the musculotendon length " + std::to_string(length_m) +
                            " m does not exceed the tendon slack length " +
                            std::to_string(p.tendon_slack_length_m) + " m");
  const double capacity = effective_activation(p, activation) * p.max_isometric_force_N;
  // Over the tendon stretch s, the muscle along the tendon is x = room - s and
  //   h(s) = Phi_S(L_slack + s) - (capacity f(L_M) + Phi_P(L_M)) cos(phi),
  // negative at s = 0. The fibre's pull is about capacity + Phi_P(L_M(room)) at most (f peaks
  // near 1, Phi_P grows with L_M, L_M with x), so h >= 0 from about the stretch at which the
  // tendon carries that pull on; the bracket grows where a model's f peaks above 1.
  auto fibre_pull = [&](double x) {
    const FiberGeometry g = fiber_geometry(p, x);
    return (capacity * force_length(p, g.length_m) + passive_fiber_force(p, g.length_m)) * g.cos_pennation;
  };
  auto h = [&](double s) { return tendon_force(p, p.tendon_slack_length_m + s) - fibre_pull(room - s); };
  double lo = 0.0;
  const double most_pull = capacity + passive_fiber_force(p, fiber_geometry(p, room).length_m);
  double hi = tendon_length_from_force(p, most_pull) - p.tendon_slack_length_m;
  for (int grow = 0; grow < 60 && hi < room && h(hi) < 0.0; ++grow) hi *= 1.5;
  if (!(h(lo) < 0.0))
    throw std::domain_error(who + "none exists: the fiber length " + std::to_string(room) +
                            " m is so far from optimal that it produces no force");
  if (hi >= room) {
    hi = room;
    if (h(hi) < 0.0)
      throw std::domain_error(who + "none exists with a positive fiber length at musculotendon length " +
                              std::to_string(length_m) + " m");
  }
  for (int it = 0; it < 200 && hi - lo > 0.0; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;  // interval at round-off
    (h(mid) < 0.0 ? lo : hi) = mid;
  }
  const double x = std::abs(h(lo)) < std::abs(h(hi)) ? lo : hi;
  return p.tendon_slack_length_m + x;
}

}  // namespace flatsos::muscles
