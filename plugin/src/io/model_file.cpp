#include "flatsos/plugin/io/model_file.hpp"

#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "flatsos/muscles/muscle_model.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"
#include "model_file_fields.hpp"
#include "model_file_millard.hpp"

namespace flatsos::plugin {

using nlohmann::json;

namespace {

using model_file::kMuscleModelKey;
using model_file::kOptionalMuscleFields;

using model_file::indexed;

// Reads fields of one JSON object, naming each by its path ("muscles[2].mass_kg") in errors,
// and rejects keys nobody read (a typo must not silently fall back to a default).
class ObjectReader {
 public:
  ObjectReader(const json& j, std::string path, const std::string& source)
      : j_(j), path_(std::move(path)), source_(source) {
    if (!j_.is_object()) fail(path_, "must be an object");
  }

  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw ModelFileError("model file '" + source_ + "': " + where + ": " + what);
  }
  std::string at(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  const std::string& path() const { return path_; }
  const std::string& source() const { return source_; }
  bool has(const std::string& key) const { return j_.contains(key); }

  const json& get(const std::string& key) {
    if (!j_.contains(key)) fail(at(key), "missing required key");
    read_.insert(key);
    return j_.at(key);
  }
  const json* find(const std::string& key) {
    if (!j_.contains(key)) return nullptr;
    read_.insert(key);
    return &j_.at(key);
  }

  double number(const json& v, const std::string& where) const {
    if (!v.is_number()) fail(where, "must be a number");
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(where, "must be finite");
    return x;
  }
  double number(const std::string& key) { return number(get(key), at(key)); }
  double positive(const std::string& key) {
    const double x = number(key);
    if (x <= 0.0) fail(at(key), "must be > 0 (got " + std::to_string(x) + ")");
    return x;
  }
  std::string string(const std::string& key) {
    const json& v = get(key);
    if (!v.is_string() || v.get<std::string>().empty()) fail(at(key), "must be a non-empty string");
    return v.get<std::string>();
  }
  Eigen::Vector3d vec3(const json& v, const std::string& where) const {
    if (!v.is_array() || v.size() != 3)
      fail(where, "must be an array of 3 numbers (wrong dimension)");
    return {number(v[0], where + "[0]"), number(v[1], where + "[1]"), number(v[2], where + "[2]")};
  }
  Eigen::Vector3d vec3(const std::string& key) { return vec3(get(key), at(key)); }
  /// An array of numbers, or (with allow_number) one number as a 1-vector.
  Eigen::VectorXd numbers(const std::string& key, bool allow_number = false) {
    const json& v = get(key);
    if (allow_number && v.is_number()) return Eigen::VectorXd::Constant(1, number(v, at(key)));
    if (!v.is_array()) fail(at(key), allow_number ? "must be a number or an array of numbers" : "must be an array of numbers");
    Eigen::VectorXd out(static_cast<Eigen::Index>(v.size()));
    for (std::size_t i = 0; i < v.size(); ++i) out[static_cast<Eigen::Index>(i)] = number(v[i], indexed(at(key), i));
    return out;
  }

  void reject_unknown_keys() const {
    for (const auto& item : j_.items())
      if (!read_.count(item.key())) fail(at(item.key()), "unknown key");
  }

 private:
  const json& j_;
  std::string path_;
  const std::string& source_;
  std::set<std::string> read_;
};

const json& array_of_objects(ObjectReader& top, const std::string& key, bool required) {
  static const json empty = json::array();
  const json* v = required ? &top.get(key) : top.find(key);
  if (!v) return empty;
  if (!v->is_array()) top.fail(key, "must be an array");
  if (required && v->empty()) top.fail(key, "must not be empty");
  return *v;
}

BodyDescription read_body(const json& j, const std::string& path, const std::string& source) {
  ObjectReader r(j, path, source);
  BodyDescription b;
  b.name = r.string("name");
  b.mass_kg = r.positive("mass_kg");
  b.mass_center_m = r.vec3("mass_center_m");
  const std::string inertia_key = "inertia_about_mass_center_kg_m2";
  const json& inertia = r.get(inertia_key);
  if (inertia.is_number()) {
    const double izz = r.number(inertia, r.at(inertia_key));
    b.principal_inertia_kg_m2 = Eigen::Vector3d::Constant(izz);
  } else if (inertia.is_array() && (inertia.size() == 3 || inertia.size() == 6)) {
    for (int k = 0; k < 3; ++k)
      b.principal_inertia_kg_m2[k] = r.number(inertia[k], indexed(r.at(inertia_key), k));
    if (inertia.size() == 6)
      for (int k = 0; k < 3; ++k)
        b.product_inertia_kg_m2[k] = r.number(inertia[3 + k], indexed(r.at(inertia_key), 3 + k));
  } else {
    r.fail(r.at(inertia_key), "must be a number (Izz) or an array of 3 or 6 numbers (wrong dimension)");
  }
  const Eigen::Vector3d& I = b.principal_inertia_kg_m2;
  if (I.minCoeff() < 0.0) r.fail(r.at(inertia_key), "moments of inertia must be >= 0");
  if (I.maxCoeff() <= 0.0) r.fail(r.at(inertia_key), "moments of inertia must not all be 0");
  const double slack = 1e-12 * I.sum();
  if (I[0] + I[1] < I[2] - slack || I[0] + I[2] < I[1] - slack || I[1] + I[2] < I[0] - slack)
    r.fail(r.at(inertia_key), "moments of inertia violate the triangle inequality");
  const Eigen::Vector3d& P = b.product_inertia_kg_m2;  // Ixy, Ixz, Iyz
  if (2.0 * std::abs(P[0]) > I[2] + slack || 2.0 * std::abs(P[1]) > I[1] + slack || 2.0 * std::abs(P[2]) > I[0] + slack)
    r.fail(r.at(inertia_key), "products of inertia too large for a physical body (need |2 Ixy| <= Izz, |2 Ixz| <= Iyy, "
                              "|2 Iyz| <= Ixx)");
  if (const json* len = r.find("length_m")) {
    b.length_m = r.number(*len, r.at("length_m"));
    if (b.length_m < 0.0) r.fail(r.at("length_m"), "must be >= 0");
  }
  r.reject_unknown_keys();
  return b;
}

// A joint's limit (joint_limit.hpp) under its type's field names.
JointLimitTorque read_joint_limit(const json& j, const std::string& path, const std::string& source, const JointFieldNames& field) {
  ObjectReader l(j, path, source);
  JointLimitTorque limit;
  limit.stiffness_N_m_per_rad = l.positive(field.stiffness);
  limit.transition_rad = l.positive(field.transition);
  if (l.has(field.damping)) {
    limit.damping_N_m_s_per_rad = l.number(field.damping);
    if (limit.damping_N_m_s_per_rad < 0.0)
      l.fail(l.at(field.damping), "must be >= 0 (got " + std::to_string(limit.damping_N_m_s_per_rad) + ")");
  }
  l.reject_unknown_keys();
  return limit;
}

JointDescription read_joint(const json& j, const std::string& path, const std::string& source) {
  ObjectReader r(j, path, source);
  JointDescription d;
  d.name = r.string("name");
  const std::string type = r.string("type");
  if (type != "pin" && type != "slider") r.fail(r.at("type"), "unsupported joint type '" + type + "' (\"pin\" or \"slider\")");
  d.type = type == "slider" ? JointType::Slider : JointType::Pin;
  d.parent = r.string("parent");
  d.child = r.string("child");
  d.location_in_parent_m = r.vec3("location_in_parent_m");
  if (d.isSlider() && !r.has("axis")) r.fail(r.at("axis"), "required for a slider: the direction it translates along");
  if (const json* axis = r.find("axis")) {
    d.axis = r.vec3(*axis, r.at("axis"));
    if (d.axis.norm() < 1e-12) r.fail(r.at("axis"), "must not be the zero vector");
    if (std::abs(d.axis.norm() - 1.0) > 1e-12) d.axis.normalize();  // a unit axis as written: the round trip is exact
  }
  if (r.has("coordinate")) d.coordinate = r.string("coordinate");
  // A range or limit in the other type's units is refused, not converted.
  const JointFieldNames& field = joint_field_names(d.type);
  const JointFieldNames& other = joint_field_names(d.isSlider() ? JointType::Pin : JointType::Slider);
  for (const char* key : {other.range, other.limit})
    if (r.has(key))
      r.fail(r.at(key), std::string("not a field of a ") + type + " (its coordinate is in " + d.coordinateUnit() + "): give \"" +
                            (key == other.range ? field.range : field.limit) + "\"");
  if (r.has(field.range)) {
    const Eigen::VectorXd range = r.numbers(field.range);
    if (range.size() != 2) r.fail(r.at(field.range), "must be [lower, upper] (2 numbers)");
    if (!(range[0] < range[1]))
      r.fail(r.at(field.range), "lower " + std::to_string(range[0]) + " must be below upper " + std::to_string(range[1]));
    d.range_rad = {range[0], range[1]};
  }
  if (const json* limit = r.find(field.limit)) {
    if (!r.has(field.range))
      r.fail(r.at(field.range), std::string("required: the joint has a ") + field.limit + ", which acts beyond its range");
    d.limit = read_joint_limit(*limit, r.at(field.limit), source, field);
  }
  r.reject_unknown_keys();
  return d;
}

void read_optional_muscle_fields(ObjectReader& r, muscles::MuscleParameters& p) {
  if (r.find(kMuscleModelKey)) {
    const std::string name = r.string(kMuscleModelKey);
    try {
      p.model = muscles::muscle_model_named(name);
      p.model->setDefaults(p);  // the muscle's own fields below override the model's defaults
    } catch (const std::invalid_argument& e) {
      r.fail(r.at(kMuscleModelKey), e.what());
    }
  }
  for (const auto& field : kOptionalMuscleFields)
    if (const json* v = r.find(field.key)) p.*field.member = r.number(*v, r.at(field.key));
  // A Millard muscle's own curves (model_file_millard.hpp), after its fiber_damping.
  model_file::apply_millard2012_fields({r.find(model_file::kMillardCurvesKey), r.find(model_file::kMaximumPennationKey),
                                        r.has("tendon_strain_at_max_force"), r.has("passive_fiber_strain_at_one_norm_force"),
                                        r.path(), r.source()},
                                       p);
}

// {"coordinates": [names], "order": k, "coefficients": [...], "held_coordinates": {name: rad}};
// the names are resolved against the joints in validate().
PolynomialPathDescription read_polynomial_path(const json& j, const std::string& path, const std::string& source) {
  ObjectReader r(j, path, source);
  PolynomialPathDescription d;
  const json& names = r.get("coordinates");
  if (!names.is_array()) r.fail(r.at("coordinates"), "must be an array of coordinate names");
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (!names[k].is_string() || names[k].get<std::string>().empty())
      r.fail(indexed(r.at("coordinates"), k), "must be a non-empty string");
    d.coordinates.push_back(names[k].get<std::string>());
  }
  const json& order = r.get("order");
  if (!order.is_number_integer() || order.get<long long>() < 0 || order.get<long long>() > 20)
    r.fail(r.at("order"), "must be an integer in [0, 20]");
  d.order = static_cast<int>(order.get<long long>());
  const Eigen::VectorXd c = r.numbers("coefficients");
  d.coefficients.assign(c.data(), c.data() + c.size());
  if (const json* held = r.find("held_coordinates")) {
    if (!held->is_object()) r.fail(r.at("held_coordinates"), "must be an object {coordinate: value_rad}");
    for (const auto& item : held->items())
      d.held_coordinates_rad[item.key()] = r.number(item.value(), r.at("held_coordinates") + "." + item.key());
  }
  r.reject_unknown_keys();
  return d;
}

MuscleDescription read_muscle(const json& j, const std::string& path, const std::string& source,
                              const muscles::MuscleParameters& defaults,
                              const std::vector<JointDescription>& joints) {
  ObjectReader r(j, path, source);
  MuscleDescription m;
  m.parameters = defaults;
  m.parameters.name = r.string("name");
  m.parameters.max_isometric_force_N = r.number("max_isometric_force_N");
  m.parameters.optimal_fiber_length_m = r.number("optimal_fiber_length_m");
  m.parameters.tendon_slack_length_m = r.number("tendon_slack_length_m");
  read_optional_muscle_fields(r, m.parameters);
  try {
    muscles::validate(m.parameters);
  } catch (const std::invalid_argument& e) {
    r.fail(path, e.what());
  }
  if (r.has("path")) {
    if (r.has("length_at_zero_angles_m") || r.has("moment_arms_m"))
      r.fail(path, "give either \"path\" or \"length_at_zero_angles_m\" with \"moment_arms_m\", not both");
    m.polynomial_path = read_polynomial_path(r.get("path"), r.at("path"), source);
    r.reject_unknown_keys();
    return m;
  }
  m.length_at_zero_angles_m = r.positive("length_at_zero_angles_m");

  const auto n = static_cast<Eigen::Index>(joints.size());
  m.moment_arms_m = Eigen::VectorXd::Zero(n);
  const std::string arms_key = "moment_arms_m";
  const json& arms = r.get(arms_key);
  if (arms.is_object()) {
    for (const auto& item : arms.items()) {
      Eigen::Index i = 0;
      while (i < n && joints[i].name != item.key()) ++i;
      if (i == n) r.fail(r.at(arms_key) + "." + item.key(), "unknown joint '" + item.key() + "'");
      m.moment_arms_m[i] = r.number(item.value(), r.at(arms_key) + "." + item.key());
    }
  } else if (arms.is_array()) {
    if (static_cast<Eigen::Index>(arms.size()) != n)
      r.fail(r.at(arms_key), "moment-arm row has " + std::to_string(arms.size()) +
                                 " entries, the model has " + std::to_string(n) +
                                 " joints (the moment-arm matrix must be N x m)");
    for (Eigen::Index i = 0; i < n; ++i)
      m.moment_arms_m[i] = r.number(arms[i], indexed(r.at(arms_key), i));
  } else {
    r.fail(r.at(arms_key), "must be an object {joint: moment arm} or an array, one per joint");
  }
  if (m.moment_arms_m.cwiseAbs().maxCoeff() == 0.0)
    r.fail(r.at(arms_key), "the muscle crosses no joint (all moment arms are 0)");
  r.reject_unknown_keys();
  return m;
}

FlatOutputDescription read_flat_output(const json& j, const std::string& path,
                                       const std::string& source,
                                       const std::vector<MuscleDescription>& muscles) {
  ObjectReader r(j, path, source);
  FlatOutputDescription y;
  y.name = r.string("name");
  const json& weights = r.get("weights");
  if (!weights.is_object() || weights.empty())
    r.fail(r.at("weights"), "must be a non-empty object {muscle: weight}");
  y.weights = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(muscles.size()));
  for (const auto& item : weights.items()) {
    Eigen::Index k = 0;
    while (k < y.weights.size() && muscles[k].parameters.name != item.key()) ++k;
    if (k == y.weights.size())
      r.fail(r.at("weights") + "." + item.key(), "unknown muscle '" + item.key() + "'");
    y.weights[k] = r.number(item.value(), r.at("weights") + "." + item.key());
  }
  r.reject_unknown_keys();
  return y;
}

}  // namespace

EffortWeights read_effort_weights(const json& j, const std::string& source, const std::vector<MuscleDescription>& muscles) {
  EffortWeights w;
  const std::string at = "effort_weights";
  if (j.is_string()) {
    const std::string kind = j.get<std::string>();
    if (kind == "flat_outputs") w.kind = EffortWeights::Kind::FlatOutputs;
    else if (kind == "normalized_tendon_force") w.kind = EffortWeights::Kind::NormalizedTendonForce;
    else
      throw ModelFileError("model file '" + source + "': " + at + ": unknown kind '" + kind +
                           "' (\"flat_outputs\", \"normalized_tendon_force\" or {\"<muscle>\": w, ...})");
    return w;
  }
  ObjectReader r(j, at, source);
  w.kind = EffortWeights::Kind::PerMuscle;
  w.per_muscle.resize(static_cast<Eigen::Index>(muscles.size()));
  for (std::size_t i = 0; i < muscles.size(); ++i) {
    const std::string& name = muscles[i].parameters.name;
    const double v = r.number(name);
    if (v < 0.0) r.fail(r.at(name), "must be >= 0 (got " + std::to_string(v) + ")");
    w.per_muscle[static_cast<Eigen::Index>(i)] = v;
  }
  r.reject_unknown_keys();  // a muscle the model does not have
  if (!(w.per_muscle.maxCoeff() > 0.0)) r.fail(at, "every weight is 0: nothing to minimize");
  return w;
}

// Angles in the file are in degrees (people write postures that way), a slider's coordinate in
// metres; SI inside. A vector of the wrong size is kept as it is, for validate() to name.
Eigen::VectorXd coordinates_from_display(Eigen::VectorXd v, const std::vector<JointDescription>& joints) {
  constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (i >= static_cast<Eigen::Index>(joints.size()) || !joints[static_cast<std::size_t>(i)].isSlider()) v[i] *= kRadPerDeg;
  return v;
}

ScenarioDescription read_scenario(const json& j, const std::string& path, const std::string& source,
                                  const std::vector<JointDescription>& joints) {
  ObjectReader r(j, path, source);
  ScenarioDescription sc;
  if (r.has("q0_deg")) sc.q0_rad = coordinates_from_display(r.numbers("q0_deg"), joints);
  if (r.has("qd0_deg_per_s")) sc.qd0_rad_per_s = coordinates_from_display(r.numbers("qd0_deg_per_s"), joints);
  if (r.has("activations")) sc.activations = r.numbers("activations");
  if (r.has("target_deg")) sc.target_q_rad = coordinates_from_display(r.numbers("target_deg"), joints);
  if (r.has("duration_s")) sc.duration_s = r.positive("duration_s");
  if (r.has("reserves_N")) sc.reserves_N = r.numbers("reserves_N", true);
  r.reject_unknown_keys();
  return sc;
}

ModelDescription parse_model_json(const std::string& json_text, const std::string& source) {
  json root;
  try {
    root = json::parse(json_text);
  } catch (const json::exception& e) {  // parse_error, also out_of_range: number overflow (1e400)
    throw ModelFileError("model file '" + source + "': not valid JSON: " + e.what());
  }
  ObjectReader top(root, "", source);
  ModelDescription model;
  if (const json* name = top.find("name")) {
    if (!name->is_string()) top.fail("name", "must be a string");
    model.name = name->get<std::string>();
  }
  if (const json* g = top.find("gravity_m_per_s2")) model.gravity_m_per_s2 = top.vec3(*g, "gravity_m_per_s2");

  const json& bodies = array_of_objects(top, "bodies", true);
  for (std::size_t i = 0; i < bodies.size(); ++i)
    model.bodies.push_back(read_body(bodies[i], indexed("bodies", i), source));
  const json& joints = array_of_objects(top, "joints", true);
  for (std::size_t i = 0; i < joints.size(); ++i)
    model.joints.push_back(read_joint(joints[i], indexed("joints", i), source));

  muscles::MuscleParameters defaults;
  if (const json* d = top.find("muscle_defaults")) {
    ObjectReader r(*d, "muscle_defaults", source);
    read_optional_muscle_fields(r, defaults);
    r.reject_unknown_keys();
  }
  const json& muscle_list = array_of_objects(top, "muscles", true);
  for (std::size_t i = 0; i < muscle_list.size(); ++i) {
    model.muscles.push_back(
        read_muscle(muscle_list[i], indexed("muscles", i), source, defaults, model.joints));
    // Checked here, before flat outputs refer to muscles by name, so the root cause is reported.
    if (model.muscleIndex(model.muscles.back().parameters.name) != static_cast<int>(i))
      top.fail(indexed("muscles", i) + ".name",
               "duplicate muscle name '" + model.muscles.back().parameters.name + "'");
  }
  const json& flat = array_of_objects(top, "flat_outputs", false);
  for (std::size_t i = 0; i < flat.size(); ++i)
    model.flat_outputs.push_back(read_flat_output(flat[i], indexed("flat_outputs", i), source, model.muscles));
  if (const json* weights = top.find("effort_weights"))
    model.effort_weights = read_effort_weights(*weights, source, model.muscles);
  if (const json* scenarios = top.find("scenarios")) {
    if (!scenarios->is_object()) top.fail("scenarios", "must be an object of named scenarios");
    for (const auto& item : scenarios->items())
      model.scenarios[item.key()] = read_scenario(item.value(), "scenarios." + item.key(), source, model.joints);
  }
  if (const json* provenance = top.find("provenance")) {
    if (!provenance->is_object()) top.fail("provenance", "must be an object");
    model.provenance_json = provenance->dump();
  }
  top.reject_unknown_keys();

  validate(model, source);
  return model;
}

bool is_opensim_model_file(const std::string& path) {
  const std::string suffix = ".osim";
  if (path.size() < suffix.size()) return false;
  for (std::size_t i = 0; i < suffix.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(path[path.size() - suffix.size() + i])) != suffix[i]) return false;
  return true;
}

ModelDescription load_model_file(const std::string& path) {
  if (is_opensim_model_file(path)) return import_opensim_file(path).model;
  std::ifstream in(path);
  if (!in) throw ModelFileError("model file '" + path + "': cannot be opened");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_model_json(text.str(), path);
}

}  // namespace flatsos::plugin
