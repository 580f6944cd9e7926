// Initial states from a states file (initial_states.hpp).

#include "flatsos/plugin/io/initial_states.hpp"

#include <cmath>
#include <stdexcept>

#include "flatsos/muscles/static_equilibrium.hpp"

namespace flatsos::plugin {

namespace {

constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;

class FirstRow {
 public:
  FirstRow(const StoTable& table, const std::string& source) : table_(table), source_(source) {
    if (table.rows.empty()) throw std::invalid_argument("states file '" + source + "': no rows");
  }
  // The first of the labels the table has, or nullptr.
  const double* find(const std::vector<std::string>& labels) const {
    for (const std::string& label : labels) {
      const int c = table_.columnIndex(label);
      if (c < 0) continue;
      const double& v = table_.rows[0][static_cast<std::size_t>(c)];
      if (!std::isfinite(v)) throw std::invalid_argument("states file '" + source_ + "', column '" + label + "': not finite");
      return &v;
    }
    return nullptr;
  }
  bool inDegrees() const { return table_.in_degrees; }
  const std::string& source() const { return source_; }

 private:
  const StoTable& table_;
  std::string source_;
};

void set_joints(const MusculoskeletalModel& model, SimTK::State& s, const FirstRow& row, std::vector<std::string>& notes) {
  Eigen::VectorXd q = model.jointAngles(s), qd = model.jointSpeeds(s);
  for (int i = 0; i < model.numJoints(); ++i) {
    const JointDescription& joint = model.description().joints[static_cast<std::size_t>(i)];
    const std::string& c = joint.coordinateName();
    const std::string path = "/jointset/" + joint.name + "/" + c;
    const double scale = row.inDegrees() && joint.type == JointType::Pin ? kRadPerDeg : 1.0;
    if (const double* v = row.find({path + "/value", c})) q[i] = *v * scale;
    else notes.push_back("coordinate " + c + ": not in the file, kept at its given value");
    if (const double* v = row.find({path + "/speed", c + "_u"})) qd[i] = *v * scale;
    else notes.push_back("speed of " + c + ": not in the file, kept at its given value");
  }
  model.setJointAngles(s, q);
  model.setJointSpeeds(s, qd);
}

void set_muscles(const MusculoskeletalModel& model, SimTK::State& s, const FirstRow& row, std::vector<std::string>& notes) {
  model.system().realize(s, SimTK::Stage::Position);
  for (int j = 0; j < model.numMuscles(); ++j) {
    const HillMuscle& muscle = model.muscle(j);
    const muscles::MuscleParameters& p = muscle.getParameters();
    const std::string path = "/forceset/" + p.name;
    if (const double* a = row.find({path + "/activation", p.name + ".activation"})) {
      if (!(*a >= 0.0 && *a <= 1.0))
        throw std::invalid_argument("states file '" + row.source() + "': activation of " + p.name + " outside [0, 1]");
      muscle.setActivation(s, *a);
    } else {
      notes.push_back("activation of " + p.name + ": not in the file, kept at its given value");
    }
    const double path_length_m = muscle.getMusculotendonLength(s);
    if (const double* tendon = row.find({path + "/tendon_length"})) {
      muscle.setTendonLength(s, *tendon);
    } else if (const double* fiber = row.find({path + "/fiber_length", p.name + ".fiber_length"})) {
      const double thickness_m = p.optimal_fiber_length_m * std::sin(p.pennation_angle_at_optimal_rad);
      if (!(*fiber > thickness_m))
        throw std::invalid_argument("states file '" + row.source() + "': fibre length of " + p.name +
                                    " is not longer than its thickness");
      muscle.setTendonLength(s, path_length_m - std::sqrt(*fiber * *fiber - thickness_m * thickness_m));
    } else {
      muscle.setTendonLength(s, muscles::static_equilibrium_tendon_length(p, path_length_m, muscle.getActivation(s)));
      notes.push_back(p.name + ": no fibre or tendon length in the file, its tendon starts in static equilibrium");
    }
  }
}

}  // namespace

std::vector<std::string> set_initial_states(const MusculoskeletalModel& model, SimTK::State& s, const StoTable& table,
                                            const std::string& source) {
  const FirstRow row(table, source);
  std::vector<std::string> notes;
  set_joints(model, s, row, notes);
  set_muscles(model, s, row, notes);
  return notes;
}

}  // namespace flatsos::plugin
