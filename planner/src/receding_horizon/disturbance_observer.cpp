#include "flatsos/planner/disturbance_observer.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace flatsos::planner {

DisturbanceObserver::DisturbanceObserver(int joints, double gain_per_s) : gain_per_s_(gain_per_s) {
  if (joints < 1) throw std::invalid_argument("disturbance observer: need at least one joint");
  if (!(gain_per_s >= 0.0) || !std::isfinite(gain_per_s))
    throw std::invalid_argument("RH controller: the disturbance observer gain must be a finite number >= 0 (1/s)");
  offset_N_m_ = Eigen::VectorXd::Zero(joints);
}

void DisturbanceObserver::follow(const Eigen::VectorXd& disturbance, double elapsed_s) {
  if (disturbance.size() != offset_N_m_.size())
    throw std::invalid_argument("disturbance observer: the measured disturbance has " + std::to_string(disturbance.size()) +
                                " entries, the model " + std::to_string(offset_N_m_.size()) + " joints");
  if (!(elapsed_s >= 0.0)) throw std::invalid_argument("disturbance observer: elapsed time must be >= 0 s");
  if (!disturbance.allFinite()) return;
  offset_N_m_ += -std::expm1(-gain_per_s_ * elapsed_s) * (disturbance - offset_N_m_);
}

}  // namespace flatsos::planner
