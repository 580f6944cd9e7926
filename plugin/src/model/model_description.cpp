#include "flatsos/plugin/model/model_description.hpp"

#include <cmath>
#include <set>
#include <string>

#include <SimTKcommon.h>

namespace flatsos::plugin {

namespace {
std::string indexed(const std::string& list, std::size_t i) { return list + "[" + std::to_string(i) + "]"; }
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
}  // namespace

void validate(const ModelDescription& model, const std::string& source) {
  auto fail = [&](const std::string& where, const std::string& what) {
    throw ModelFileError("model file '" + source + "': " + where + ": " + what);
  };
  if (model.bodies.empty()) fail("bodies", "must not be empty");
  if (model.joints.empty()) fail("joints", "must not be empty");
  if (model.muscles.empty()) fail("muscles", "must not be empty");
  if (!model.gravity_m_per_s2.allFinite()) fail("gravity_m_per_s2", "must be finite");

  std::set<std::string> body_names;
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const auto& b = model.bodies[i];
    if (b.name == "ground") fail(indexed("bodies", i) + ".name", "'ground' is reserved");
    if (!body_names.insert(b.name).second)
      fail(indexed("bodies", i) + ".name", "duplicate body name '" + b.name + "'");
    if (!(b.mass_kg > 0.0) || !std::isfinite(b.mass_kg)) fail(indexed("bodies", i) + ".mass_kg", "must be > 0");
    // Simbody stores the inertia about the body origin: a mass centre far out (found by the fuzzer:
    // 1e38 m) swamps the central inertia in rounding and Simbody aborts on the result.
    if (!b.mass_center_m.allFinite() || b.mass_center_m.norm() > 100.0)
      fail(indexed("bodies", i) + ".mass_center_m", "must be finite and within 100 m of the body frame");
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
  std::set<std::string> attached = {"ground"}, joint_names;
  for (std::size_t i = 0; i < model.joints.size(); ++i) {
    const auto& jd = model.joints[i];
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
  for (const auto& b : model.bodies)
    if (!attached.count(b.name)) fail("bodies", "body '" + b.name + "' has no joint");

  std::set<std::string> muscle_names;
  for (std::size_t j = 0; j < model.muscles.size(); ++j) {
    const auto& m = model.muscles[j];
    const std::string at = indexed("muscles", j);
    if (!muscle_names.insert(m.parameters.name).second)
      fail(at + ".name", "duplicate muscle name '" + m.parameters.name + "'");
    try {
      muscles::validate(m.parameters);
    } catch (const std::invalid_argument& e) {
      fail(at, e.what());
    }
    if (m.moment_arms_m.size() != model.numJoints())
      fail(at + ".moment_arms_m", "must have one entry per joint (the moment-arm matrix must be N x m)");
    if (!m.moment_arms_m.allFinite()) fail(at + ".moment_arms_m", "must be finite");
    if (!(m.length_at_zero_angles_m > 0.0) || !std::isfinite(m.length_at_zero_angles_m))
      fail(at + ".length_at_zero_angles_m", "must be > 0");
  }
  for (const auto& [name, sc] : model.scenarios) {
    const std::string at = "scenarios." + name;
    auto sized = [&](const Eigen::VectorXd& v, int size, const char* field, const char* per) {
      if (v.size() != 0 && v.size() != size)
        fail(at + "." + field, "must have one value per " + std::string(per) + " (" + std::to_string(size) + "), got " +
                                   std::to_string(v.size()));
      if (!v.allFinite()) fail(at + "." + field, "must be finite");
    };
    sized(sc.q0_rad, model.numJoints(), "q0_deg", "joint");
    sized(sc.qd0_rad_per_s, model.numJoints(), "qd0_deg_per_s", "joint");
    sized(sc.target_q_rad, model.numJoints(), "target_deg", "joint");
    sized(sc.activations, model.numMuscles(), "activations", "muscle");
    if (sc.activations.size() && !(sc.activations.minCoeff() > 0.0 && sc.activations.maxCoeff() <= 1.0))
      fail(at + ".activations", "must lie in (0, 1]");
    if (sc.reserves_N.size() != 1) sized(sc.reserves_N, model.numMuscles(), "reserves_N", "muscle (or one for all)");
    if (!sc.reserves_N.allFinite() || (sc.reserves_N.size() && sc.reserves_N.minCoeff() < 0.0))
      fail(at + ".reserves_N", "must be finite and >= 0");
    if (!(sc.duration_s >= 0.0) || !std::isfinite(sc.duration_s)) fail(at + ".duration_s", "must be > 0");
  }
  if (!model.flat_outputs.empty()) {
    const int expected = model.numMuscles() - model.numJoints();
    if (static_cast<int>(model.flat_outputs.size()) != expected)
      fail("flat_outputs", "E must have m - N = " + std::to_string(expected) + " rows (" +
                               std::to_string(model.numMuscles()) + " muscles, " +
                               std::to_string(model.numJoints()) + " joints), the file has " +
                               std::to_string(model.flat_outputs.size()));
    std::set<std::string> names;
    for (std::size_t k = 0; k < model.flat_outputs.size(); ++k) {
      const auto& y = model.flat_outputs[k];
      if (!names.insert(y.name).second)
        fail(indexed("flat_outputs", k) + ".name", "duplicate flat output name '" + y.name + "'");
      if (y.weights.size() != model.numMuscles() || !y.weights.allFinite())
        fail(indexed("flat_outputs", k) + ".weights", "must have one finite weight per muscle");
    }
  }
}

Eigen::MatrixXd ModelDescription::momentArmMatrix() const {
  Eigen::MatrixXd a(numJoints(), numMuscles());
  for (int j = 0; j < numMuscles(); ++j) a.col(j) = muscles[j].moment_arms_m;
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
