#include "flatsos/muscles/muscle_parameters.hpp"

#include "flatsos/muscles/muscle_model.hpp"
#include "parameter_checks.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace flatsos::muscles {

void reject(const MuscleParameters& p, const char* field, double value, const char* requirement) {
  std::ostringstream msg;
  msg << "muscle '" << (p.name.empty() ? std::string("<unnamed>") : p.name) << "': " << field
      << " = " << value << " is invalid (" << requirement << ")";
  throw std::invalid_argument(msg.str());
}

void require_positive(const MuscleParameters& p, const char* field, double value) {
  if (!std::isfinite(value)) reject(p, field, value, "must be a finite number");
  if (value <= 0.0) reject(p, field, value, "must be > 0");
}

void validate(const MuscleParameters& p) {
  require_positive(p, "max_isometric_force_N", p.max_isometric_force_N);
  require_positive(p, "optimal_fiber_length_m", p.optimal_fiber_length_m);
  require_positive(p, "tendon_slack_length_m", p.tendon_slack_length_m);
  require_positive(p, "tendon_strain_at_max_force", p.tendon_strain_at_max_force);
  require_positive(p, "force_length_width", p.force_length_width);
  require_positive(p, "max_shortening_velocity_in_optimal_lengths_per_s",
                   p.max_shortening_velocity_in_optimal_lengths_per_s);
  require_positive(p, "activation_time_constant_s", p.activation_time_constant_s);
  require_positive(p, "deactivation_time_constant_s", p.deactivation_time_constant_s);
  if (!std::isfinite(p.activation_floor) || p.activation_floor <= 0.0 || p.activation_floor >= 1.0)
    reject(p, "activation_floor", p.activation_floor,
           "must be in (0, 1): the contraction dynamics divide by the activation");
  const double phi0 = p.pennation_angle_at_optimal_rad;
  if (!std::isfinite(phi0) || phi0 < 0.0 || phi0 >= 1.5707963267948966)
    reject(p, "pennation_angle_at_optimal_rad", phi0, "must be in [0, pi/2) rad");
  const double e0 = p.passive_fiber_strain_at_one_norm_force;
  if (!std::isfinite(e0) || e0 < 0.0)
    reject(p, "passive_fiber_strain_at_one_norm_force", e0, "must be > 0, or 0 for no passive force");
  if (!std::isfinite(p.fiber_damping) || p.fiber_damping < 0.0)
    reject(p, "fiber_damping", p.fiber_damping, "must be >= 0 (0: no damping)");
  if (!p.model)
    throw std::invalid_argument("muscle '" + (p.name.empty() ? std::string("<unnamed>") : p.name) +
                                "': no muscle model");
  p.model->validate(p);
}

}  // namespace flatsos::muscles
