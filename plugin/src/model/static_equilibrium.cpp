#include "flatsos/plugin/model/static_equilibrium.hpp"

namespace flatsos::plugin {

void equilibrate_tendons(const MusculoskeletalModel& model, SimTK::State& s,
                         const Eigen::VectorXd& activations) {
  model.setActivations(s, activations);
  // The force elements' own path lengths: their geometry when they simulate one.
  model.system().realize(s, SimTK::Stage::Position);
  for (int j = 0; j < model.numMuscles(); ++j)
    model.muscle(j).setTendonLength(s, static_equilibrium_tendon_length(model.muscle(j).getParameters(),
                                                                        model.muscle(j).getMusculotendonLength(s),
                                                                        activations[j]));
}

}  // namespace flatsos::plugin
