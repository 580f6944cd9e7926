#include "flatness/input_checks.hpp"

#include <sstream>
#include <stdexcept>
#include <string>

namespace flatsos::planner::detail {

void require(const Eigen::VectorXd& v, int size, const char* what) {
  if (v.size() != size)
    throw std::invalid_argument(std::string(what) + ": expected " + std::to_string(size) + " values, got " +
                                std::to_string(v.size()));
  if (!v.allFinite()) throw std::invalid_argument(std::string(what) + ": values must be finite (NaN or Inf given)");
}

void require_reserves(const Eigen::VectorXd& r, int m) {
  require(r, m, "reserves");
  if (r.minCoeff() < 0.0) throw std::invalid_argument("reserves: tendon-force reserves must be >= 0 N");
}

void require_initial_muscle_state(const FlatOutputMap& flat, const MuscleState& initial) {
  const int m = flat.numMuscles();
  require(initial.activation, m, "initial activations");
  require(initial.tendon_length_m, m, "initial tendon lengths");
  for (int j = 0; j < m; ++j) {
    const auto& mp = flat.model().muscle(j).getParameters();
    if (!(initial.activation[j] > 0.0 && initial.activation[j] <= 1.0))
      throw std::invalid_argument("initial state: activation of '" + mp.name + "' is " + std::to_string(initial.activation[j]) +
                                  ", outside (0, 1]");
    if (!(initial.tendon_length_m[j] > mp.tendon_slack_length_m))
      throw std::invalid_argument("initial state: tendon of '" + mp.name + "' is slack (" +
                                  std::to_string(initial.tendon_length_m[j]) + " m <= slack length " +
                                  std::to_string(mp.tendon_slack_length_m) + " m): flat outputs need taut tendons");
  }
}

void require_taut_tendons_possible(const plugin::MusculoskeletalModel& model, const Eigen::VectorXd& q, const char* what) {
  for (int j = 0; j < model.numMuscles(); ++j) {
    const double L = model.musculotendonLength(j, q);
    const auto& mp = model.muscle(j).getParameters();
    if (!(L > mp.tendon_slack_length_m)) {
      std::ostringstream why;
      why << what << ": the musculotendon path of '" << mp.name << "' would be " << L
          << " m long there, not longer than its tendon slack length " << mp.tendon_slack_length_m
          << " m, so its tendon cannot be taut (are the angles in radians?)";
      throw std::invalid_argument(why.str());
    }
  }
}

}  // namespace flatsos::planner::detail
