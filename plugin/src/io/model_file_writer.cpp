// model_json_text(): the writing half of model files (reading: model_file.cpp).
#include "flatsos/plugin/io/model_file.hpp"

#include <nlohmann/json.hpp>

#include "flatsos/muscles/muscle_model.hpp"
#include "model_file_fields.hpp"
#include "model_file_millard.hpp"

namespace flatsos::plugin {

using nlohmann::json;

namespace {

using model_file::kMuscleModelKey;
using model_file::kOptionalMuscleFields;

json vec3_json(const Eigen::Vector3d& v) { return json::array({v[0], v[1], v[2]}); }
json vector_json(const Eigen::VectorXd& v) {
  json out = json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) out.push_back(v[i]);
  return out;
}
// Per joint as people read it: degrees for a pin, metres for a slider (the reader's inverse).
json display_json(const Eigen::VectorXd& v, const std::vector<JointDescription>& joints) {
  json out = json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i)
    out.push_back(v[i] * (i < static_cast<Eigen::Index>(joints.size()) ? joints[static_cast<std::size_t>(i)].displayPerSI()
                                                                        : 180.0 / 3.14159265358979323846));
  return out;
}

json joint_json(const JointDescription& d) {
  const JointFieldNames& field = joint_field_names(d.type);
  json joint = {{"name", d.name},
                {"type", joint_type_name(d.type)},
                {"parent", d.parent},
                {"child", d.child},
                {"location_in_parent_m", vec3_json(d.location_in_parent_m)},
                {"axis", vec3_json(d.axis)}};
  if (!d.coordinate.empty()) joint["coordinate"] = d.coordinate;
  if (d.hasRange()) joint[field.range] = json::array({d.range_rad[0], d.range_rad[1]});
  if (d.limit.stiffness_N_m_per_rad > 0.0)
    joint[field.limit] = {{field.stiffness, d.limit.stiffness_N_m_per_rad},
                          {field.transition, d.limit.transition_rad},
                          {field.damping, d.limit.damping_N_m_s_per_rad}};
  return joint;
}

json muscle_json(const MuscleDescription& m, const std::vector<JointDescription>& joints) {
  const muscles::MuscleParameters& p = m.parameters;
  json out = {{"name", p.name},
              {"max_isometric_force_N", p.max_isometric_force_N},
              {"optimal_fiber_length_m", p.optimal_fiber_length_m},
              {"tendon_slack_length_m", p.tendon_slack_length_m}};
  muscles::MuscleParameters defaults;
  if (p.model && p.model != defaults.model) {
    out[kMuscleModelKey] = p.model->name();
    // The defaults the reader starts from: the named model's (a Millard muscle's own curves
    // differ from them, and are written below).
    muscles::muscle_model_named(p.model->name())->setDefaults(defaults);
  }
  for (const auto& field : kOptionalMuscleFields)
    if (p.*field.member != defaults.*field.member) out[field.key] = p.*field.member;
  model_file::write_millard2012_fields(p, out);
  if (m.polynomial_path) {
    const PolynomialPathDescription& d = *m.polynomial_path;
    out["path"] = {{"coordinates", d.coordinates}, {"order", d.order}, {"coefficients", d.coefficients}};
    if (!d.held_coordinates_rad.empty()) out["path"]["held_coordinates"] = d.held_coordinates_rad;
  } else {
    out["length_at_zero_angles_m"] = m.length_at_zero_angles_m;
    json arms = json::object();
    for (std::size_t i = 0; i < joints.size(); ++i)
      if (m.moment_arms_m[static_cast<Eigen::Index>(i)] != 0.0) arms[joints[i].name] = m.moment_arms_m[static_cast<Eigen::Index>(i)];
    out["moment_arms_m"] = arms;
  }
  return out;
}

}  // namespace

std::string model_json_text(const ModelDescription& model) {
  json out = json::object();
  if (!model.name.empty()) out["name"] = model.name;
  out["gravity_m_per_s2"] = vec3_json(model.gravity_m_per_s2);
  for (const auto& b : model.bodies) {
    json body = {{"name", b.name}, {"mass_kg", b.mass_kg}, {"mass_center_m", vec3_json(b.mass_center_m)}};
    const Eigen::Vector3d& I = b.principal_inertia_kg_m2;
    const Eigen::Vector3d& P = b.product_inertia_kg_m2;
    body["inertia_about_mass_center_kg_m2"] = json::array({I[0], I[1], I[2], P[0], P[1], P[2]});
    if (b.length_m > 0.0) body["length_m"] = b.length_m;
    out["bodies"].push_back(body);
  }
  for (const auto& d : model.joints) out["joints"].push_back(joint_json(d));
  for (const auto& m : model.muscles) out["muscles"].push_back(muscle_json(m, model.joints));
  for (const auto& y : model.flat_outputs) {
    json weights = json::object();
    for (std::size_t j = 0; j < model.muscles.size(); ++j)
      if (y.weights[static_cast<Eigen::Index>(j)] != 0.0) weights[model.muscles[j].parameters.name] = y.weights[static_cast<Eigen::Index>(j)];
    out["flat_outputs"].push_back({{"name", y.name}, {"weights", weights}});
  }
  switch (model.effort_weights.kind) {
    case EffortWeights::Kind::Default: break;
    case EffortWeights::Kind::FlatOutputs: out["effort_weights"] = "flat_outputs"; break;
    case EffortWeights::Kind::NormalizedTendonForce: out["effort_weights"] = "normalized_tendon_force"; break;
    case EffortWeights::Kind::PerMuscle:
      for (std::size_t j = 0; j < model.muscles.size(); ++j)
        out["effort_weights"][model.muscles[j].parameters.name] = model.effort_weights.per_muscle[static_cast<Eigen::Index>(j)];
      break;
  }
  for (const auto& [name, sc] : model.scenarios) {
    json s = json::object();
    if (sc.q0_rad.size()) s["q0_deg"] = display_json(sc.q0_rad, model.joints);
    if (sc.qd0_rad_per_s.size()) s["qd0_deg_per_s"] = display_json(sc.qd0_rad_per_s, model.joints);
    if (sc.activations.size()) s["activations"] = vector_json(sc.activations);
    if (sc.target_q_rad.size()) s["target_deg"] = display_json(sc.target_q_rad, model.joints);
    if (sc.duration_s > 0.0) s["duration_s"] = sc.duration_s;
    if (sc.reserves_N.size()) s["reserves_N"] = vector_json(sc.reserves_N);
    out["scenarios"][name] = s;
  }
  if (!model.provenance_json.empty()) out["provenance"] = json::parse(model.provenance_json);
  return out.dump(2) + "\n";
}

}  // namespace flatsos::plugin
