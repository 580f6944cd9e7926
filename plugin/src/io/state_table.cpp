#include "flatsos/plugin/io/state_table.hpp"

namespace flatsos::plugin {

StoTable make_state_table(const MusculoskeletalModel& model, const std::string& name) {
  StoTable t;
  t.name = name;
  t.columns.push_back("time");
  for (const auto& j : model.description().joints) {
    t.columns.push_back("/jointset/" + j.name + "/q");
    t.columns.push_back("/jointset/" + j.name + "/qdot");
  }
  for (const auto& m : model.description().muscles)
    for (const char* what : {"excitation", "activation", "tendon_length", "tendon_force",
                             "fiber_length", "fiber_velocity"})
      t.columns.push_back("/forceset/" + m.parameters.name + "/" + what);
  return t;
}

void append_state_row(const MusculoskeletalModel& model, const SimTK::State& s, StoTable& table) {
  model.system().realize(s, SimTK::Stage::Velocity);
  std::vector<double> row;
  row.reserve(table.columns.size());
  row.push_back(s.getTime());
  for (int i = 0; i < model.numJoints(); ++i) {
    row.push_back(model.joint(i).getOneQ(s, 0));
    row.push_back(model.joint(i).getOneU(s, 0));
  }
  for (int j = 0; j < model.numMuscles(); ++j) {
    const HillMuscle& m = model.muscle(j);
    row.push_back(m.getExcitation(s));
    row.push_back(m.getActivation(s));
    row.push_back(m.getTendonLength(s));
    row.push_back(m.getTendonForce(s));
    row.push_back(m.getFiberLength(s));
    row.push_back(-m.getFiberShorteningVelocity(s));
  }
  table.rows.push_back(std::move(row));
}

}  // namespace flatsos::plugin
