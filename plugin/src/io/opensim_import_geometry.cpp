// Import from the model's own GeometryPaths (opensim_import.hpp): the options are checked as the
// importer checks them, the paths fitted over the kept ranges with the others held, and the
// fit's report handed to the importer for the provenance and the notes.

#include <nlohmann/json.hpp>

#include "flatsos/plugin/io/opensim_import.hpp"
#include "flatsos/plugin/paths/polynomial_path_fit.hpp"
#include "opensim_reduction.hpp"

namespace flatsos::plugin {

namespace {

using opensim_import::fixed;
using opensim_import::kDegPerRad;

PathFitOptions fit_options(const OpenSimModel& osim, const OpenSimImportOptions& options) {
  PathFitOptions fit;
  for (const std::string& k : options.keep) {
    const auto given = options.ranges.find(k);
    fit.ranges[k] = given != options.ranges.end() ? given->second : osim.coordinate(k)->range;
  }
  fit.held = options.hold;
  return fit;
}

// A posture as people read it: "r_shoulder_elev 12.5 deg, r_elbow_flex 80.0 deg".
std::string posture_text(const OpenSimModel& osim, const PathFitReport& r) {
  std::string text;
  for (std::size_t k = 0; k < r.coordinates.size(); ++k) {
    const bool rotational = osim.coordinate(r.coordinates[k])->rotational;
    const double value = r.worst_length_posture[k];
    text += (k ? ", " : "") + r.coordinates[k] + " " +
            (rotational ? fixed(value * kDegPerRad, 1) + " deg" : fixed(value, 4) + " m");
  }
  return text;
}

nlohmann::json report_json(const OpenSimModel& osim, const PathFit& fit) {
  nlohmann::json out = nlohmann::json::object();
  for (const PathFitReport& r : fit.reports) {
    out[r.muscle] = {{"coordinates", r.coordinates},
                     {"order", r.order},
                     {"samples", r.samples},
                     {"tolerances_met", r.tolerances_met},
                     {"length_rms_m", r.length_rms_m},
                     {"length_max_m", r.length_max_m},
                     {"largest_length_error_at", posture_text(osim, r)},
                     {"moment_arm_rms_m", r.moment_arm_rms_m},
                     {"moment_arm_max_m", r.moment_arm_max_m}};
  }
  return out;
}

}  // namespace

OpenSimImport import_opensim_model(const OpenSimModel& osim, const OpenSimGeometryPaths& geometry,
                                   const OpenSimImportOptions& options) {
  const opensim_import::Reduction checked(osim, options);  // the importer's own checks first
  const PathFit fit = fit_polynomial_paths(osim, geometry, fit_options(osim, options));
  OpenSimImportOptions with_fit = options;
  with_fit.path_fit_json = report_json(osim, fit).dump();
  OpenSimImport imported = import_opensim_model(osim, fit.paths, with_fit);
  for (const PathFitReport& r : fit.reports) {
    if (imported.model.muscleIndex(r.muscle) < 0) continue;
    imported.notes.push_back("path of " + r.muscle + " fitted (order " + std::to_string(r.order) + "): length error up to " +
                             fixed(1e3 * r.length_max_m, 3) + " mm (RMS " + fixed(1e3 * r.length_rms_m, 3) +
                             " mm, largest at " + posture_text(osim, r) + "), moment arm up to " +
                             fixed(1e3 * r.moment_arm_max_m, 3) + " mm");
  }
  return imported;
}

}  // namespace flatsos::plugin
