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
  const double k = p.tendon_stiffness_N_per_m2();
  const double capacity = effective_activation(p, activation) * p.max_isometric_force_N;
  // h(x) = k x^2 - capacity f(room - x) over the tendon stretch x: negative at x = 0, and
  // non-negative at x = sqrt(capacity / k) since f <= 1; the fiber must keep a positive length.
  auto h = [&](double x) { return k * x * x - capacity * force_length(p, room - x); };
  double lo = 0.0;
  double hi = std::sqrt(capacity / k);
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
