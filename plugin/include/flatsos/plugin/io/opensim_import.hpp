#pragma once
// An OpenSim model and its fitted muscle paths reduced to a flatsos model: the kept coordinates
// become pin joints about their own axes (exact for a joint that is one rotation), or, when they
// are translations, slider joints along them (a joint that is one translation at 1 m per m;
// opensim_slider.hpp), every other coordinate is held (in the kinematics and inside
// the path polynomials), bodies welded to ground are dropped and bodies beyond a kept joint are
// lumped into its child, and every muscle whose fitted length depends on a kept coordinate is
// brought along with its OpenSim parameters. What is approximated is measured and recorded in
// the model's provenance (docs/method/opensim_import.md).

#include <array>
#include <map>
#include <string>
#include <vector>

#include "flatsos/plugin/io/opensim_model.hpp"
#include "flatsos/plugin/io/opensim_paths.hpp"
#include "flatsos/plugin/model/model_description.hpp"
#include "flatsos/plugin/paths/geometry_path.hpp"

namespace flatsos::plugin {

struct OpenSimImportOptions {
  std::string name;               ///< the model's name; empty: the OpenSim model's
  std::vector<std::string> keep;  ///< coordinates that become pin or slider joints (at most one per joint)
  /// Values of coordinates that are not kept (rad, or m for translations); others are held at 0,
  /// and a coordinate coupled to another (CoordinateCouplerConstraint) follows it.
  std::map<std::string, double> hold;
  /// Ranges of kept coordinates (rad, or m for translations), inside the OpenSim coordinate's own range; a kept
  /// coordinate not listed keeps its OpenSim range.
  std::map<std::string, std::array<double, 2>> ranges;
  /// A muscle whose tendon is slack somewhere in the range (the fitted length does not exceed
  /// the tendon slack length) is left out and reported; with refuse_slack_muscles, refused.
  bool refuse_slack_muscles = false;
  /// Millard2012EquilibriumMuscle with flatsos' default laws (Richter & Warner's) and the file's
  /// common parameters instead of Millard's curves, as the importer made them before it modelled
  /// them (the shipped seated_knee_r and sagittal_leg_r models were made so).
  bool millard_with_flatsos_laws = false;
  std::string osim_source, paths_source;  ///< file names, for the provenance
  long slack_check_postures = 20000;      ///< postures per muscle for the slack check
  /// Thelen2003Muscle as OpenSim 2.x modelled it (thelen2003_opensim2), to reproduce results of
  /// that time; OpenSim 4's model otherwise.
  bool opensim_2_muscles = false;
  /// Every muscle replaced by a DeGrooteFregly2016Muscle as OpenSim Moco's
  /// ModOpReplaceMusclesWithDeGrooteFregly2016 does (the smooth muscle MocoInverse and MocoTrack
  /// are run with); with ignore_passive_fiber_forces also Moco's
  /// ModOpIgnorePassiveFiberForcesDGF. Not with opensim_2_muscles.
  bool degroote_fregly2016_muscles = false;
  bool ignore_passive_fiber_forces = false;
  /// Set by the GeometryPath overload: the fit's report as JSON (provenance "path_fit").
  std::string path_fit_json;
};

struct OpenSimImport {
  ModelDescription model;  ///< validated; provenance_json says what was read, held and approximated
  /// One line per thing a user should know (muscles left out and why, approximations, how far
  /// the pins are from OpenSim's joints), also in the provenance.
  std::vector<std::string> notes;
};

/// Throws OpenSimModelError naming the coordinate, joint, muscle or value for: a kept or held
/// coordinate the model does not have, one given twice or both kept and held, two kept
/// coordinates of one joint, a kept coupled coordinate, a kept translation whose joint does not slide 1 m per m
/// along one direction, a held value or range outside the coordinate's range, a
/// muscle that crosses a kept joint without a fitted path (or whose path names a coordinate the
/// model lacks), a slack muscle with refuse_slack_muscles, no muscle left.
OpenSimImport import_opensim_model(const OpenSimModel& osim, const std::vector<OpenSimPolynomialPath>& paths,
                                   const OpenSimImportOptions& options);

/// The same from the model's own GeometryPaths: each muscle's length is fitted by a polynomial
/// of the kept coordinates over their ranges, the others held (polynomial_path_fit.hpp); the
/// fit's errors per muscle go into the provenance ("path_fit") and the notes. Throws as above
/// and as fit_polynomial_paths does.
OpenSimImport import_opensim_model(const OpenSimModel& osim, const OpenSimGeometryPaths& geometry,
                                   const OpenSimImportOptions& options);

/// An .osim file as a user downloads it, imported with OpenSim's own settings: every coordinate
/// that is not locked, not driven by a coupler and the only free one of its joint is kept, with
/// OpenSim's range; the others are held at their default values (noted); the muscle paths are
/// fitted to the GeometryPaths. Throws as the reader and the importer do, and OpenSimModelError
/// when no coordinate can be kept (naming the joints with several, which need --keep).
/// With simulate_geometry, each muscle also carries its GeometryPath for simulation
/// (MuscleDescription::path_geometry; planning keeps the fitted polynomials). With
/// opensim_2_muscles, Thelen muscles and cylinder wrapping are OpenSim 2.x's
/// (OpenSimGeometryPaths::opensim_2_wrapping).
OpenSimImport import_opensim_file(const std::string& osim_file, bool simulate_geometry = false,
                                  bool opensim_2_muscles = false);

/// How import_opensim_file reads a file (the programs' --paths, --opensim-2-muscles,
/// --degroote-muscles and --ignore-passive-fiber-forces; Python's Model keywords).
struct OpenSimFileOptions {
  bool simulate_geometry = false;
  bool opensim_2_muscles = false;
  bool degroote_fregly2016_muscles = false;  ///< OpenSimImportOptions' of the same name
  bool ignore_passive_fiber_forces = false;  ///< with degroote_fregly2016_muscles only
};

/// The same with these options. Throws std::invalid_argument for opensim_2_muscles with
/// degroote_fregly2016_muscles, or ignore_passive_fiber_forces without it.
OpenSimImport import_opensim_file(const std::string& osim_file, const OpenSimFileOptions& options);

}  // namespace flatsos::plugin
