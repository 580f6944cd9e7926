#include "flatsos/plugin/io/state_table.hpp"

namespace flatsos::plugin {

namespace {
std::string coordinate_path(const MusculoskeletalModel& model, int joint) {
  const JointDescription& j = model.description().joints.at(static_cast<std::size_t>(joint));
  return "/jointset/" + j.name + "/" + j.coordinateName();
}
}  // namespace

std::string coordinate_value_column(const MusculoskeletalModel& model, int joint) {
  return coordinate_path(model, joint) + "/value";
}
std::string coordinate_speed_column(const MusculoskeletalModel& model, int joint) {
  return coordinate_path(model, joint) + "/speed";
}

StoTable make_state_table(const MusculoskeletalModel& model, const std::string& name) {
  StoTable t;
  t.name = name;
  t.columns.push_back("time");
  for (int i = 0; i < model.numJoints(); ++i) {
    t.columns.push_back(coordinate_value_column(model, i));
    t.columns.push_back(coordinate_speed_column(model, i));
  }
  for (const auto& m : model.description().muscles)
    for (const char* what : {"activation", "tendon_length", "tendon_force", "fiber_length", "fiber_velocity"})
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
    row.push_back(m.getActivation(s));
    row.push_back(m.getTendonLength(s));
    row.push_back(m.getTendonForce(s));
    row.push_back(m.getFiberLength(s));
    row.push_back(-m.getFiberShorteningVelocity(s));
  }
  table.rows.push_back(std::move(row));
}

StoTable make_controls_table(const MusculoskeletalModel& model, const std::string& name) {
  StoTable t;
  t.name = name;
  t.columns.push_back("time");
  for (const auto& m : model.description().muscles) t.columns.push_back("/forceset/" + m.parameters.name);
  return t;
}

void append_controls_row(const MusculoskeletalModel& model, const SimTK::State& s, StoTable& table) {
  std::vector<double> row;
  row.reserve(table.columns.size());
  row.push_back(s.getTime());
  for (int j = 0; j < model.numMuscles(); ++j) row.push_back(model.muscle(j).getExcitation(s));
  table.rows.push_back(std::move(row));
}

}  // namespace flatsos::plugin
