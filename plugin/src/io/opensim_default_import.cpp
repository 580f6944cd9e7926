// import_opensim_file (opensim_import.hpp): the options a user who names an .osim file where a
// model is expected would choose, from the file itself.

#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "flatsos/plugin/io/opensim_import.hpp"
#include "flatsos/plugin/paths/opensim_path_geometry.hpp"
#include "flatsos/plugin/paths/polynomial_path_fit.hpp"
#include "opensim_range_narrowing.hpp"
#include "opensim_reduction.hpp"

namespace flatsos::plugin {

namespace {

bool free_coordinate(const OpenSimModel& osim, const OpenSimCoordinate& c) {
  return !c.locked && !osim.couplerOf(c.name);
}

// Keep each joint's coordinate when it is the joint's only free one; hold everything else at
// OpenSim's default value. Joints with several free coordinates are named in a note.
OpenSimImportOptions default_options(const OpenSimModel& osim, std::vector<std::string>& notes) {
  OpenSimImportOptions options;
  std::map<std::string, int> free_per_joint;
  for (const OpenSimCoordinate& c : osim.coordinates)
    if (free_coordinate(osim, c)) ++free_per_joint[c.joint];
  std::string several;
  for (const OpenSimCoordinate& c : osim.coordinates) {
    if (free_coordinate(osim, c) && free_per_joint[c.joint] == 1) {
      options.keep.push_back(c.name);
    } else if (!osim.couplerOf(c.name)) {
      options.hold[c.name] = c.default_value;
      if (free_coordinate(osim, c) && several.find("'" + c.joint + "'") == std::string::npos)
        several += (several.empty() ? "'" : ", '") + c.joint + "'";
    }
  }
  if (!several.empty())
    notes.push_back("joints with several free coordinates are held at their default values: " + several +
                    " (opensim_to_model --keep chooses one coordinate per joint)");
  if (options.keep.empty())
    throw OpenSimModelError("no coordinate to keep: no joint has exactly one free (unlocked, uncoupled) coordinate" +
                            (several.empty() ? std::string() : "; joints with several: " + several) +
                            "; choose them with opensim_to_model --keep");
  return options;
}

// OpenSim's ranges narrowed to where the reduced model is usable (opensim_range_narrowing.hpp),
// judged on coarse fits, refitted over each narrowed range until it holds; each narrowed range
// is noted.
void narrow_ranges(const OpenSimModel& osim, const OpenSimGeometryPaths& geometry, OpenSimImportOptions& options,
                   std::vector<std::string>& notes) {
  PathFitOptions coarse;
  for (const std::string& k : options.keep) coarse.ranges[k] = osim.coordinate(k)->range;
  coarse.held = options.hold;
  coarse.max_samples = 1000;
  const auto given = coarse.ranges;
  for (int round = 0; round < 4; ++round) {
    const auto narrowed = opensim_import::narrow_to_usable_ranges(osim, fit_polynomial_paths(osim, geometry, coarse), coarse.ranges);
    if (narrowed == coarse.ranges) break;
    coarse.ranges = narrowed;
  }
  for (const auto& [name, range] : coarse.ranges) {
    options.ranges[name] = range;
    if (range == given.at(name)) continue;
    const OpenSimCoordinate& c = *osim.coordinate(name);
    notes.push_back("range of " + name + " narrowed from " + opensim_import::shown(c, given.at(name)[0]) + " .. " +
                    opensim_import::shown(c, given.at(name)[1]) + " to " + opensim_import::shown(c, range[0]) + " .. " +
                    opensim_import::shown(c, range[1]) +
                    ": beyond it a tendon would be slack or no muscle would pull one way (opensim_to_model --range chooses)");
  }
}

}  // namespace

OpenSimImport import_opensim_file(const std::string& osim_file, bool simulate_geometry, bool opensim_2_muscles) {
  OpenSimFileOptions o;
  o.simulate_geometry = simulate_geometry;
  o.opensim_2_muscles = opensim_2_muscles;
  return import_opensim_file(osim_file, o);
}

OpenSimImport import_opensim_file(const std::string& osim_file, const OpenSimFileOptions& file_options) {
  if (file_options.opensim_2_muscles && file_options.degroote_fregly2016_muscles)
    throw std::invalid_argument("opensim_2_muscles and degroote_fregly2016_muscles exclude each other: the muscles are "
                                "either OpenSim 2.x's Thelen muscles or DeGroote-Fregly's");
  if (file_options.ignore_passive_fiber_forces && !file_options.degroote_fregly2016_muscles)
    throw std::invalid_argument("ignore_passive_fiber_forces applies to DeGroote-Fregly muscles (OpenSim Moco's "
                                "ModOpIgnorePassiveFiberForcesDGF): ask for degroote_fregly2016_muscles too");
  const auto shared_osim = std::make_shared<const OpenSimModel>(read_opensim_model(osim_file));
  const OpenSimModel& osim = *shared_osim;
  std::vector<std::string> notes;
  OpenSimImportOptions options = default_options(osim, notes);
  options.osim_source = std::filesystem::path(osim_file).filename().string();
  options.opensim_2_muscles = file_options.opensim_2_muscles;
  options.degroote_fregly2016_muscles = file_options.degroote_fregly2016_muscles;
  options.ignore_passive_fiber_forces = file_options.ignore_passive_fiber_forces;
  auto read_geometry = std::make_shared<OpenSimGeometryPaths>(read_opensim_geometry_paths(osim_file));
  read_geometry->opensim_2_wrapping = file_options.opensim_2_muscles;  // results of OpenSim 2.x: its wrapping too
  const std::shared_ptr<const OpenSimGeometryPaths> shared_geometry = read_geometry;
  const OpenSimGeometryPaths& geometry = *shared_geometry;
  narrow_ranges(osim, geometry, options, notes);
  OpenSimImport imported = import_opensim_model(osim, geometry, options);
  if (file_options.simulate_geometry) {
    attach_geometry_paths(imported.model, shared_osim, shared_geometry, options.hold);
    notes.push_back("simulation uses the GeometryPaths (via points, wrapping) as OpenSim does; planning the fitted paths");
  }
  imported.notes.insert(imported.notes.begin(), notes.begin(), notes.end());
  nlohmann::json provenance = nlohmann::json::parse(imported.model.provenance_json);
  provenance["notes"] = imported.notes;
  provenance["import"] = "import_opensim_file: OpenSim's coordinates, ranges and default values";
  imported.model.provenance_json = provenance.dump();
  return imported;
}

}  // namespace flatsos::plugin
