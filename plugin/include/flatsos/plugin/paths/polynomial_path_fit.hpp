#pragma once
// Smooth muscle paths for planning, fitted to an OpenSim model's GeometryPaths the way OpenSim's
// PolynomialPathFitter fits them: for each muscle, a MultivariatePolynomialFunction of the
// coordinates its length depends on, its coefficients the least-squares solution of the lengths
// and the moment arms (as OpenSim's moment arm solver gives them) at sampled postures together,
// its order the lowest from min_order to max_order whose RMS errors meet the tolerances. Here the
// samples cover the coordinates' ranges (a grid for up to three coordinates, a Halton sequence
// beyond), the other coordinates held, and the fit is checked at postures between the samples:
// the report gives each muscle's RMS and largest errors and where the largest length error is
// (a path that jumps, as a wrap switches sides, cannot be followed by a polynomial).

#include <array>
#include <map>
#include <string>
#include <vector>

#include "flatsos/plugin/io/opensim_model.hpp"
#include "flatsos/plugin/io/opensim_paths.hpp"
#include "flatsos/plugin/paths/geometry_path.hpp"

namespace flatsos::plugin {

struct PathFitOptions {
  /// The coordinates the polynomials are functions of, each over its range (rad, or m).
  std::map<std::string, std::array<double, 2>> ranges;
  /// Values of the model's other coordinates (rad, or m; absent ones are 0). A coordinate a
  /// coupler drives from a fitted coordinate follows it unless it is listed here.
  std::map<std::string, double> held;
  int min_order = 2, max_order = 6;        ///< OpenSim's defaults
  double length_tolerance_m = 1e-4;        ///< RMS over the samples (OpenSim's default)
  double moment_arm_tolerance_m = 1e-4;    ///< RMS per coordinate (OpenSim's default)
  int max_samples = 4000;                  ///< samples per muscle (the grid's size is at most this)
};

struct PathFitReport {
  std::string muscle;
  std::vector<std::string> coordinates;  ///< the polynomial's arguments, in order
  int order = 0;
  int samples = 0;                        ///< fitting postures; the check uses as many between them
  double length_rms_m = 0.0, length_max_m = 0.0;          ///< at the check postures
  double moment_arm_rms_m = 0.0, moment_arm_max_m = 0.0;  ///< over every coordinate
  std::vector<double> worst_length_posture;  ///< the coordinates' values where length_max_m is
  bool tolerances_met = false;               ///< at the samples, as OpenSim decides
};

struct PathFit {
  std::vector<OpenSimPolynomialPath> paths;  ///< as a FunctionBasedPathSet would give them
  std::vector<PathFitReport> reports;        ///< one per path, same order
};

/// Fits every muscle with a GeometryPath whose length depends on a coordinate in
/// options.ranges. Throws OpenSimModelError naming the coordinate or muscle for: a coordinate
/// the model lacks, a range that is empty, reversed or not finite, orders outside 0 <= min <=
/// max <= 12, tolerances that are not positive, a path flatsos cannot evaluate
/// (GeometryPathEvaluator's errors), a length or moment arm that is not finite at a sample.
PathFit fit_polynomial_paths(const OpenSimModel& model, const OpenSimGeometryPaths& geometry, const PathFitOptions& options);

}  // namespace flatsos::plugin
