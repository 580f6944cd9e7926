#pragma once
// Model files: JSON text -> a validated ModelDescription (the format is documented in
// model/model_description.hpp). A bad file throws ModelFileError naming the field.

#include <string>

#include "flatsos/plugin/model/model_description.hpp"

namespace flatsos::plugin {

/// Parse and validate a model from JSON text. `source` names it in messages (a path).
ModelDescription parse_model_json(const std::string& json_text, const std::string& source);
/// Read, parse and validate a model file; an OpenSim model (.osim) is imported with its own
/// settings (import_opensim_file, opensim_import.hpp: its notes are in the provenance).
ModelDescription load_model_file(const std::string& path);
/// True for a path ending in ".osim" (any case).
bool is_opensim_model_file(const std::string& path);
/// The model as a model file's JSON text (parse_model_json reads it back to an equal model;
/// scenario angles go through degrees). Muscle fields equal to MuscleParameters' defaults are
/// left out.
std::string model_json_text(const ModelDescription& model);

}  // namespace flatsos::plugin
