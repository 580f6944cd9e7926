#pragma once
// A model file's Millard muscle (muscle_model "millard2012"): its curve properties
// ("millard2012_curves", OpenSim's property names under the curve keys of millard2012_fields.hpp)
// and maximum pennation, read into a Millard2012Muscle instance and written back so that
// parsing what was written gives the same curves. Shared by model_file.cpp and
// model_file_writer.cpp; errors are ModelFileErrors naming the field's path.

#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "flatsos/muscles/millard2012_muscle.hpp"
#include "flatsos/muscles/muscle_parameters.hpp"

namespace flatsos::plugin::model_file {

inline constexpr const char* kMillardCurvesKey = "millard2012_curves";
inline constexpr const char* kMaximumPennationKey = "maximum_pennation_angle_rad";

/// What a muscle object states for its Millard model (nullptr: not stated), and where.
struct MillardFields {
  const nlohmann::json* curves = nullptr;
  const nlohmann::json* maximum_pennation_rad = nullptr;
  bool tendon_strain_stated = false, passive_strain_stated = false;  ///< the two strain fields
  std::string path;    ///< the muscle's path in the file, "muscles[2]"
  std::string source;  ///< the file, for errors
};

/// Gives p a new Millard2012Muscle when p's model is one and the fields, or a fiber_damping of
/// the other kind (damped / undamped) than p's model, ask for another; its strain fields then
/// follow the new curves unless stated. Curves stated replace the inherited ones whole
/// (properties left out: OpenSim's defaults); without them the inherited curves are kept.
/// Throws ModelFileError naming the field for a field given to a muscle of another model, a
/// wrong type, an unknown key, or a value the muscle refuses.
void apply_millard2012_fields(const MillardFields& fields, muscles::MuscleParameters& p);

/// The fields that differ from a muscle_model_named("millard2012") of the same damping kind:
/// whole curves (optional properties resolved), maximum pennation. Adds nothing for other models.
void write_millard2012_fields(const muscles::MuscleParameters& p, nlohmann::json& muscle);

}  // namespace flatsos::plugin::model_file
