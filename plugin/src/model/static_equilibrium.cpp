#include "flatsos/plugin/model/static_equilibrium.hpp"

namespace flatsos::plugin {

void equilibrate_tendons(const MusculoskeletalModel& model, SimTK::State& s,
                         const Eigen::VectorXd& activations) {
  model.setActivations(s, activations);
  const Eigen::VectorXd lengths = model.musculotendonLengths(model.jointAngles(s));
  for (int j = 0; j < model.numMuscles(); ++j)
    model.muscle(j).setTendonLength(
        s, static_equilibrium_tendon_length(model.muscle(j).getParameters(), lengths[j], activations[j]));
}

}  // namespace flatsos::plugin
