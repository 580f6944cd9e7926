// Millard muscles in model files (model_file_millard.hpp).
#include "model_file_millard.hpp"

#include <cmath>
#include <map>
#include <set>
#include <stdexcept>
#include <type_traits>

#include "flatsos/plugin/model/model_description.hpp"  // ModelFileError
#include "millard2012_fields.hpp"

namespace flatsos::plugin::model_file {

using nlohmann::json;

namespace {

// OpenSim's MIN_NONZERO_DAMPING_COEFFICIENT: below it a Millard muscle is undamped.
constexpr double kMinimumDamping = 0.001;

[[noreturn]] void fail(const MillardFields& f, const std::string& where, const std::string& what) {
  throw ModelFileError("model file '" + f.source + "': " + f.path + "." + where + ": " + what);
}

double finite_number(const MillardFields& f, const json& v, const std::string& where) {
  if (!v.is_number()) fail(f, where, "must be a number");
  const double x = v.get<double>();
  if (!std::isfinite(x)) fail(f, where, "must be finite");
  return x;
}

// The curves object over OpenSim's defaults; every key must name a curve and a property.
muscles::Millard2012CurveParameters read_curves(const MillardFields& f) {
  const json& curves = *f.curves;
  if (!curves.is_object()) fail(f, kMillardCurvesKey, "must be an object {curve: {property: value}}");
  muscles::Millard2012CurveParameters out;
  std::map<std::string, std::set<std::string>> known;  // curve -> its properties
  millard2012_fields::for_each_property(out, [&](const char*, const char* curve, const char* property, auto&) {
    known[curve].insert(property);
  });
  for (const auto& item : curves.items()) {
    const std::string where = std::string(kMillardCurvesKey) + "." + item.key();
    const auto curve = known.find(item.key());
    if (curve == known.end()) fail(f, where, "unknown curve");
    if (!item.value().is_object()) fail(f, where, "must be an object {property: value}");
    for (const auto& property : item.value().items())
      if (!curve->second.count(property.key())) fail(f, where + "." + property.key(), "unknown property");
  }
  millard2012_fields::for_each_property(out, [&](const char*, const char* curve, const char* property, auto& field) {
    const auto c = curves.find(curve);
    if (c == curves.end()) return;
    if (const auto v = c->find(property); v != c->end())
      field = finite_number(f, *v, std::string(kMillardCurvesKey) + "." + curve + "." + property);
  });
  return out;
}

bool damped(double fiber_damping) { return fiber_damping >= kMinimumDamping; }

// The Millard muscle the fields ask for (p's own when they ask for nothing new).
std::shared_ptr<const muscles::MuscleModel> millard2012_model(const MillardFields& f, const muscles::MuscleParameters& p) {
  const auto* inherited = dynamic_cast<const muscles::Millard2012Muscle*>(p.model.get());
  if (!inherited) {
    if (f.curves) fail(f, kMillardCurvesKey, "only for a muscle whose muscle_model is \"millard2012\"");
    if (f.maximum_pennation_rad) fail(f, kMaximumPennationKey, "only for a muscle whose muscle_model is \"millard2012\"");
    return p.model;
  }
  if (!f.curves && !f.maximum_pennation_rad && damped(p.fiber_damping) == inherited->damped()) return p.model;
  const muscles::Millard2012CurveParameters curves = f.curves ? read_curves(f) : inherited->curveParameters();
  const double maximum_pennation_rad = f.maximum_pennation_rad
                                           ? finite_number(f, *f.maximum_pennation_rad, kMaximumPennationKey)
                                           : inherited->maximumPennationAngle();
  muscles::Millard2012MuscleConfiguration configuration;
  configuration.fiber_damping = p.fiber_damping;
  try {
    return std::make_shared<const muscles::Millard2012Muscle>(curves, configuration, maximum_pennation_rad);
  } catch (const std::invalid_argument& e) {
    const bool pennation = std::string(e.what()).find("maximum_pennation_angle") != std::string::npos;
    fail(f, pennation || !f.curves ? kMaximumPennationKey : kMillardCurvesKey, e.what());
  }
}

}  // namespace

void apply_millard2012_fields(const MillardFields& fields, muscles::MuscleParameters& p) {
  const std::shared_ptr<const muscles::MuscleModel> model = millard2012_model(fields, p);
  if (model == p.model) return;
  p.model = model;
  muscles::MuscleParameters own;
  model->setDefaults(own);
  if (!fields.tendon_strain_stated) p.tendon_strain_at_max_force = own.tendon_strain_at_max_force;
  if (!fields.passive_strain_stated) p.passive_fiber_strain_at_one_norm_force = own.passive_fiber_strain_at_one_norm_force;
}

void write_millard2012_fields(const muscles::MuscleParameters& p, json& muscle) {
  const auto* model = dynamic_cast<const muscles::Millard2012Muscle*>(p.model.get());
  if (!model) return;
  muscles::Millard2012MuscleConfiguration configuration;
  configuration.fiber_damping = model->damped() ? configuration.fiber_damping : 0.0;
  const muscles::Millard2012Muscle reference(muscles::Millard2012CurveParameters{}, configuration);
  // Every property of every curve: optional ones are resolved in an instance's parameters.
  auto values = [](const muscles::Millard2012CurveParameters& c) {
    std::map<std::string, json> out;
    millard2012_fields::for_each_property(c, [&](const char*, const char* curve, const char* property, const auto& field) {
      if constexpr (std::is_same_v<std::decay_t<decltype(field)>, double>) out[curve][property] = field;
      else if (field) out[curve][property] = *field;
    });
    return out;
  };
  const std::map<std::string, json> given = values(model->curveParameters()), defaults = values(reference.curveParameters());
  for (const auto& [curve, properties] : given)
    if (properties != defaults.at(curve)) muscle[kMillardCurvesKey][curve] = properties;
  if (model->maximumPennationAngle() != reference.maximumPennationAngle())
    muscle[kMaximumPennationKey] = model->maximumPennationAngle();
}

}  // namespace flatsos::plugin::model_file
