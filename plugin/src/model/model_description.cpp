#include "flatsos/plugin/model/model_description.hpp"
#include "flatsos/plugin/model/posture_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <vector>
#include <string>

#include <SimTKcommon.h>

#include "../io/model_file_fields.hpp"

namespace flatsos::plugin {

namespace {
using model_file::indexed;

// Simbody's round trip of a body's inertia: about the mass centre -> about the body origin ->
// back, each checked by SimTK::Inertia as Simbody checks it.
bool central_inertia_survives_shift(const BodyDescription& b) {
  try {
    const Eigen::Vector3d& c = b.mass_center_m;
    const SimTK::Vec3 com(c[0], c[1], c[2]);
    const SimTK::Inertia about_com(SimTK::Vec3(b.principal_inertia_kg_m2[0], b.principal_inertia_kg_m2[1], b.principal_inertia_kg_m2[2]),
                                   SimTK::Vec3(b.product_inertia_kg_m2[0], b.product_inertia_kg_m2[1], b.product_inertia_kg_m2[2]));
    (void)SimTK::MassProperties(b.mass_kg, com, about_com.shiftFromMassCenter(com, b.mass_kg)).calcCentralInertia();
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

int joint_by_name(const ModelDescription& model, const std::string& name) {
  for (int i = 0; i < model.numJoints(); ++i)
    if (model.joints[static_cast<std::size_t>(i)].name == name || model.joints[static_cast<std::size_t>(i)].coordinateName() == name)
      return i;
  return -1;
}

// The path of a muscle, or ModelFileError naming the field (`source` for the message).
muscles::MusculotendonPath build_path(const ModelDescription& model, int j, const std::string& source) {
  const MuscleDescription& m = model.muscles[static_cast<std::size_t>(j)];
  const std::string at = indexed("muscles", static_cast<std::size_t>(j));
  auto fail = [&](const std::string& where, const std::string& what) -> void {
    throw ModelFileError("model file '" + source + "': " + where + ": " + what);
  };
  if (!m.polynomial_path) {
    if (m.moment_arms_m.size() != model.numJoints())
      fail(at + ".moment_arms_m", "must have one entry per joint (the moment-arm matrix must be N x m)");
    if (!m.moment_arms_m.allFinite()) fail(at + ".moment_arms_m", "must be finite");
    if (!(m.length_at_zero_angles_m > 0.0) || !std::isfinite(m.length_at_zero_angles_m))
      fail(at + ".length_at_zero_angles_m", "must be > 0");
    if (m.moment_arms_m.cwiseAbs().maxCoeff() == 0.0)
      fail(at + ".moment_arms_m", "the muscle crosses no joint (all moment arms are 0)");
    try {
      return muscles::MusculotendonPath::constantMomentArms(
          m.length_at_zero_angles_m, std::vector<double>(m.moment_arms_m.data(), m.moment_arms_m.data() + m.moment_arms_m.size()));
    } catch (const std::invalid_argument& e) {
      fail(at + ".moment_arms_m", e.what());
    }
  }
  const PolynomialPathDescription& pd = *m.polynomial_path;
  const std::string pat = at + ".path";
  if (m.moment_arms_m.size() != 0 || m.length_at_zero_angles_m != 0.0)
    fail(at, "give either \"path\" or \"length_at_zero_angles_m\" with \"moment_arms_m\", not both");
  std::vector<muscles::PathCoordinate> coordinates;
  std::set<std::string> seen;
  for (std::size_t k = 0; k < pd.coordinates.size(); ++k) {
    const std::string& name = pd.coordinates[k];
    const std::string where = pat + ".coordinates[" + std::to_string(k) + "]";
    if (!seen.insert(name).second) fail(where, "coordinate '" + name + "' is listed twice");
    const int joint = joint_by_name(model, name);
    const auto held = pd.held_coordinates_rad.find(name);
    if (joint >= 0 && held != pd.held_coordinates_rad.end())
      fail(pat + ".held_coordinates." + name, "'" + name + "' is a joint of the model: it cannot also be held");
    if (joint < 0 && held == pd.held_coordinates_rad.end())
      fail(where, "unknown coordinate '" + name + "': neither a joint of the model nor listed in held_coordinates");
    if (held != pd.held_coordinates_rad.end() && !std::isfinite(held->second))
      fail(pat + ".held_coordinates." + name, "must be finite");
    coordinates.push_back(joint >= 0 ? muscles::PathCoordinate{joint, 0.0} : muscles::PathCoordinate{-1, held->second});
  }
  for (const auto& [name, value] : pd.held_coordinates_rad)
    if (!seen.count(name)) fail(pat + ".held_coordinates." + name, "'" + name + "' is not one of the path's coordinates");
  muscles::LengthPolynomial polynomial;
  try {
    polynomial = muscles::LengthPolynomial(static_cast<int>(pd.coordinates.size()), pd.order, pd.coefficients);
  } catch (const std::invalid_argument& e) {
    fail(pat, std::string("coefficients: ") + e.what());
  }
  muscles::MusculotendonPath path;
  try {
    path = muscles::MusculotendonPath(std::move(polynomial), std::move(coordinates), model.numJoints());
  } catch (const std::invalid_argument& e) {  // e.g. one joint under its name and its coordinate's
    fail(pat + ".coordinates", e.what());
  }
  if (path.crossedJoints().empty()) fail(pat, "the muscle crosses no joint (its length depends on no joint of the model)");
  return path;
}

// validate()'s checks, in the order they run; each throws ModelFileError naming the field.
class Validation {
 public:
  Validation(const ModelDescription& model, const std::string& source) : model_(model), source_(source) {}

  void run() const {
    if (model_.bodies.empty()) fail("bodies", "must not be empty");
    if (model_.joints.empty()) fail("joints", "must not be empty");
    if (model_.muscles.empty()) fail("muscles", "must not be empty");
    if (!model_.gravity_m_per_s2.allFinite()) fail("gravity_m_per_s2", "must be finite");
    const std::set<std::string> body_names = checkBodies();
    checkJointTree(body_names);
    checkJointRangesAndLimits();
    checkEffortWeights();
    checkMuscles();
    checkScenarios();
    checkFlatOutputs();
  }

 private:
  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw ModelFileError("model file '" + source_ + "': " + where + ": " + what);
  }

  // The bodies' names, once each checked.
  std::set<std::string> checkBodies() const {
    std::set<std::string> body_names;
    for (std::size_t i = 0; i < model_.bodies.size(); ++i) {
      const auto& b = model_.bodies[i];
      if (b.name == "ground") fail(indexed("bodies", i) + ".name", "'ground' is reserved");
      if (!body_names.insert(b.name).second)
        fail(indexed("bodies", i) + ".name", "duplicate body name '" + b.name + "'");
      if (!(b.mass_kg > 0.0) || !std::isfinite(b.mass_kg)) fail(indexed("bodies", i) + ".mass_kg", "must be > 0");
      // Simbody stores the inertia about the body origin: a mass centre far out (found by the fuzzer:
      // 1e38 m) swamps the central inertia in rounding and Simbody aborts on the result.
      if (!b.mass_center_m.allFinite() || b.mass_center_m.norm() > 100.0)
        fail(indexed("bodies", i) + ".mass_center_m", "must be finite and within 100 m of the body frame");
      checkInertia(b, i);
    }
    return body_names;
  }

  void checkInertia(const BodyDescription& b, std::size_t i) const {
    // The conditions Simbody's Inertia demands (it throws its own message otherwise).
    const Eigen::Vector3d& I = b.principal_inertia_kg_m2;
    const Eigen::Vector3d& P = b.product_inertia_kg_m2;  // Ixy, Ixz, Iyz
    if (!I.allFinite() || I.minCoeff() < 0.0)
      fail(indexed("bodies", i) + ".principal_inertia_kg_m2", "moments of inertia must be finite and >= 0");
    const double slack = 1e-12 * I.sum();
    if (I[0] + I[1] < I[2] - slack || I[0] + I[2] < I[1] - slack || I[1] + I[2] < I[0] - slack)
      fail(indexed("bodies", i) + ".principal_inertia_kg_m2", "moments of inertia violate the triangle inequality");
    if (!P.allFinite() || 2.0 * std::abs(P[0]) > I[2] + slack || 2.0 * std::abs(P[1]) > I[1] + slack ||
        2.0 * std::abs(P[2]) > I[0] + slack)
      fail(indexed("bodies", i) + ".product_inertia_kg_m2",
           "products of inertia too large for a physical body (need |2 Ixy| <= Izz, |2 Ixz| <= Iyy, |2 Iyz| <= Ixx)");
    // Simbody keeps the inertia about the body origin and shifts it back to the mass centre while
    // it builds the system, where its complaint cannot be caught (it aborts the program). A mass
    // large enough (found by the fuzzer: 8e98 kg) swamps the central inertia in that round trip's
    // rounding: the same round trip here names the field instead.
    if (!central_inertia_survives_shift(b))
      fail(indexed("bodies", i) + ".mass_kg", "too large for the body's inertia: its moment about the joint swamps "
                                              "the inertia about the mass centre in rounding");
  }

  // Joints: parents first, every body attached exactly once (a tree rooted at ground).
  void checkJointTree(const std::set<std::string>& body_names) const {
    std::set<std::string> attached = {"ground"}, joint_names;
    for (std::size_t i = 0; i < model_.joints.size(); ++i) {
      const auto& jd = model_.joints[i];
      const std::string at = indexed("joints", i);
      if (!joint_names.insert(jd.name).second) fail(at + ".name", "duplicate joint name '" + jd.name + "'");
      if (jd.coordinate.find('/') != std::string::npos) fail(at + ".coordinate", "must be a name without '/'");
      if (!body_names.count(jd.child)) fail(at + ".child", "unknown body '" + jd.child + "'");
      if (jd.parent != "ground" && !body_names.count(jd.parent))
        fail(at + ".parent", "unknown body '" + jd.parent + "'");
      if (!attached.count(jd.parent))
        fail(at + ".parent", "body '" + jd.parent + "' is not attached yet: list parent joints first");
      if (!attached.insert(jd.child).second)
        fail(at + ".child", "body '" + jd.child + "' already has a joint");
    }
    for (const auto& b : model_.bodies)
      if (!attached.count(b.name)) fail("bodies", "body '" + b.name + "' has no joint");
  }

  // Each joint's type and axis; its range and limit under the field names of its type.
  void checkJointRangesAndLimits() const {
    for (std::size_t i = 0; i < model_.joints.size(); ++i) {
      const JointDescription& jd = model_.joints[i];
      if (jd.type != JointType::Pin && jd.type != JointType::Slider)
        fail(indexed("joints", i) + ".type", "unknown joint type (\"pin\" or \"slider\")");
      if (!jd.axis.allFinite() || !(jd.axis.norm() > 1e-12))
        fail(indexed("joints", i) + ".axis", "must be a finite vector, not the zero vector");
      const JointFieldNames& field = joint_field_names(jd.type);
      const auto& r = jd.range_rad;
      const bool unbounded = r[0] == -std::numeric_limits<double>::infinity() && r[1] == std::numeric_limits<double>::infinity();
      if (!unbounded && !(std::isfinite(r[0]) && std::isfinite(r[1]) && r[0] < r[1]))
        fail(indexed("joints", i) + "." + field.range, "must be [lower, upper] with finite lower < upper (got [" +
                                                         std::to_string(r[0]) + ", " + std::to_string(r[1]) + "])");
      const JointLimitTorque& limit = jd.limit;
      const std::string at = indexed("joints", i) + "." + field.limit + ".";
      if (limit.stiffness_N_m_per_rad != 0.0 || limit.transition_rad != 0.0 || limit.damping_N_m_s_per_rad != 0.0) {
        if (!(std::isfinite(limit.stiffness_N_m_per_rad) && limit.stiffness_N_m_per_rad > 0.0))
          fail(at + field.stiffness, "must be finite and > 0 (got " + std::to_string(limit.stiffness_N_m_per_rad) + ")");
        if (!(std::isfinite(limit.transition_rad) && limit.transition_rad > 0.0))
          fail(at + field.transition, "must be finite and > 0 (got " + std::to_string(limit.transition_rad) + ")");
        if (!(std::isfinite(limit.damping_N_m_s_per_rad) && limit.damping_N_m_s_per_rad >= 0.0))
          fail(at + field.damping, "must be finite and >= 0 (got " + std::to_string(limit.damping_N_m_s_per_rad) + ")");
        if (!jd.hasRange())
          fail(indexed("joints", i) + "." + field.range, std::string("required: the joint has a ") + field.limit +
                                                             ", which acts beyond its range");
      }
    }
  }

  void checkEffortWeights() const {
    if (model_.effort_weights.kind != EffortWeights::Kind::PerMuscle) return;
    const Eigen::VectorXd& w = model_.effort_weights.per_muscle;
    if (w.size() != static_cast<Eigen::Index>(model_.muscles.size()))
      fail("effort_weights", "needs one weight per muscle (" + std::to_string(model_.muscles.size()) + "), got " +
                                 std::to_string(w.size()));
    for (Eigen::Index j = 0; j < w.size(); ++j)
      if (!(std::isfinite(w[j]) && w[j] >= 0.0))
        fail("effort_weights." + model_.muscles[static_cast<std::size_t>(j)].parameters.name,
             "must be finite and >= 0 (got " + std::to_string(w[j]) + ")");
    if (!(w.size() > 0 && w.maxCoeff() > 0.0)) fail("effort_weights", "every weight is 0: nothing to minimize");
  }

  void checkMuscles() const {
    std::set<std::string> muscle_names;
    for (std::size_t j = 0; j < model_.muscles.size(); ++j) {
      const auto& m = model_.muscles[j];
      const std::string at = indexed("muscles", j);
      if (!muscle_names.insert(m.parameters.name).second)
        fail(at + ".name", "duplicate muscle name '" + m.parameters.name + "'");
      try {
        muscles::validate(m.parameters);
      } catch (const std::invalid_argument& e) {
        fail(at, e.what());
      }
      checkMusclePath(j);
    }
  }

  void checkMusclePath(std::size_t j) const {
    const auto& m = model_.muscles[j];
    const std::string at = indexed("muscles", j);
    const muscles::MusculotendonPath path = build_path(model_, static_cast<int>(j), source_);
    const std::vector<int>& crossed = path.crossedJoints();
    bool ranged = true;
    for (int i : crossed) ranged = ranged && model_.joints[static_cast<std::size_t>(i)].hasRange();
    if (!path.hasConstantMomentArms())
      for (int i : crossed)
        if (!model_.joints[static_cast<std::size_t>(i)].hasRange())
          fail(indexed("joints", static_cast<std::size_t>(i)) + "." + joint_field_names(model_.joints[static_cast<std::size_t>(i)].type).range,
               "required: muscle '" + m.parameters.name + "' has a path that depends on posture over this joint (a polynomial "
               "is trusted only over a stated range)");
    // Over the range of motion the unit must stay longer than its slack tendon: otherwise the
    // tendon goes slack (no force, no flatness) or the length is not even positive.
    if (ranged)
      for_each_posture(model_, crossed, 20000, [&](const Eigen::VectorXd& q) {
        const double length = path.length(q.data());
        if (!(length > m.parameters.tendon_slack_length_m))
          fail(at + (m.polynomial_path ? ".path" : ".length_at_zero_angles_m"),
               "the musculotendon length " + std::to_string(length) + " m at " + describe_posture(model_, crossed, q) +
                   " does not exceed the tendon slack length " + std::to_string(m.parameters.tendon_slack_length_m) +
                   " m: the tendon would be slack there");
      });
  }

  void checkScenarios() const {
    for (const auto& [name, sc] : model_.scenarios) {
      const std::string at = "scenarios." + name;
      auto sized = [&](const Eigen::VectorXd& v, int size, const char* field, const char* per) {
        if (v.size() != 0 && v.size() != size)
          fail(at + "." + field, "must have one value per " + std::string(per) + " (" + std::to_string(size) + "), got " +
                                     std::to_string(v.size()));
        if (!v.allFinite()) fail(at + "." + field, "must be finite");
      };
      sized(sc.q0_rad, model_.numJoints(), "q0_deg", "joint");
      sized(sc.qd0_rad_per_s, model_.numJoints(), "qd0_deg_per_s", "joint");
      sized(sc.target_q_rad, model_.numJoints(), "target_deg", "joint");
      sized(sc.activations, model_.numMuscles(), "activations", "muscle");
      if (sc.activations.size() && !(sc.activations.minCoeff() > 0.0 && sc.activations.maxCoeff() <= 1.0))
        fail(at + ".activations", "must lie in (0, 1]");
      if (sc.reserves_N.size() != 1) sized(sc.reserves_N, model_.numMuscles(), "reserves_N", "muscle (or one for all)");
      if (!sc.reserves_N.allFinite() || (sc.reserves_N.size() && sc.reserves_N.minCoeff() < 0.0))
        fail(at + ".reserves_N", "must be finite and >= 0");
      if (!(sc.duration_s >= 0.0) || !std::isfinite(sc.duration_s)) fail(at + ".duration_s", "must be > 0");
    }
  }

  void checkFlatOutputs() const {
    if (model_.flat_outputs.empty()) return;
    const int expected = model_.numMuscles() - model_.numJoints();
    if (static_cast<int>(model_.flat_outputs.size()) != expected)
      fail("flat_outputs", "E must have m - N = " + std::to_string(expected) + " rows (" +
                               std::to_string(model_.numMuscles()) + " muscles, " +
                               std::to_string(model_.numJoints()) + " joints), the file has " +
                               std::to_string(model_.flat_outputs.size()));
    std::set<std::string> names;
    for (std::size_t k = 0; k < model_.flat_outputs.size(); ++k) {
      const auto& y = model_.flat_outputs[k];
      if (!names.insert(y.name).second)
        fail(indexed("flat_outputs", k) + ".name", "duplicate flat output name '" + y.name + "'");
      if (y.weights.size() != model_.numMuscles() || !y.weights.allFinite())
        fail(indexed("flat_outputs", k) + ".weights", "must have one finite weight per muscle");
    }
  }

  const ModelDescription& model_;
  const std::string& source_;
};

}  // namespace

void validate(const ModelDescription& model, const std::string& source) { Validation(model, source).run(); }

const char* joint_type_name(JointType type) { return type == JointType::Slider ? "slider" : "pin"; }

const JointFieldNames& joint_field_names(JointType type) {
  static const JointFieldNames pin{"range_rad", "limit_torque", "stiffness_N_m_per_rad", "transition_rad", "damping_N_m_s_per_rad"};
  static const JointFieldNames slider{"range_m", "limit_force", "stiffness_N_per_m", "transition_m", "damping_N_s_per_m"};
  return type == JointType::Slider ? slider : pin;
}

muscles::MusculotendonPath ModelDescription::musclePath(int j) const {
  if (j < 0 || j >= numMuscles()) throw std::out_of_range("muscle index " + std::to_string(j) + " out of range");
  return build_path(*this, j, name.empty() ? "model" : name);
}

bool ModelDescription::hasConstantMomentArms() const {
  for (const auto& m : muscles)
    if (m.polynomial_path && m.polynomial_path->order > 1) return false;
  return true;
}

Eigen::MatrixXd ModelDescription::momentArmMatrix() const {
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(numJoints(), numMuscles());
  std::vector<double> r(static_cast<std::size_t>(numJoints()));
  const std::vector<double> q(static_cast<std::size_t>(numJoints()), 0.0);
  for (int j = 0; j < numMuscles(); ++j) {
    const muscles::MusculotendonPath path = musclePath(j);
    if (!path.hasConstantMomentArms())
      throw std::logic_error("muscle '" + muscles[static_cast<std::size_t>(j)].parameters.name +
                             "': its moment arms depend on posture, so the model has no constant moment-arm matrix");
    path.momentArms(q.data(), r.data());
    for (int i = 0; i < numJoints(); ++i) a(i, j) = r[static_cast<std::size_t>(i)];
  }
  return a;
}

Eigen::MatrixXd ModelDescription::flatOutputMatrix() const {
  Eigen::MatrixXd e(static_cast<Eigen::Index>(flat_outputs.size()), numMuscles());
  for (std::size_t k = 0; k < flat_outputs.size(); ++k)
    e.row(static_cast<Eigen::Index>(k)) = flat_outputs[k].weights.transpose();
  return e;
}

int ModelDescription::muscleIndex(const std::string& n) const {
  for (int j = 0; j < numMuscles(); ++j)
    if (muscles[j].parameters.name == n) return j;
  return -1;
}

const ScenarioDescription* ModelDescription::scenario(const std::string& scenario_name) const {
  const auto it = scenarios.find(scenario_name);
  return it == scenarios.end() ? nullptr : &it->second;
}

int ModelDescription::jointIndex(const std::string& n) const {
  for (int i = 0; i < numJoints(); ++i)
    if (joints[i].name == n) return i;
  return -1;
}

}  // namespace flatsos::plugin
