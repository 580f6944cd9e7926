#pragma once
// A measured motion (a coordinates table such as an inverse-kinematics .mot) made smooth and
// differentiable the way OpenSim's InverseDynamicsTool does it before it computes joint torques
// (OpenSim 2.3-2.4, InverseDynamicsTool::run; Storage::pad, lowpassIIR and resample;
// GCVSplineSet), so flatsos and OpenSim evaluate the same q, qdot and qddot:
//   1. pad each column (and the time column) at both ends by half the row count, reflected
//      through the end samples (pad_by_point_reflection);
//   2. resample onto a uniform grid: the smallest padded time step, from the first padded time,
//      the step added repeatedly while it stays <= the last padded time (uniform_time_grid), the
//      values read off a natural quintic spline through the padded samples;
//   3. third-order Butterworth low-pass, forward and backward, at that step (butterworth_filter);
//   4. degrees to radians for the rotational columns when the table is in degrees;
//   5. a natural quintic interpolating spline through the filtered grid (natural_quintic_spline);
//   6. the tool's output times: the grid samples from the last one at or before the table's first
//      time to the last one at or before its last time (report_sample_range).
// A negative cutoff means no filtering, as in OpenSim: steps 1-3 and 6 are skipped and the
// splines go through the table's own samples.

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "flatsos/plugin/io/natural_quintic_spline.hpp"
#include "flatsos/plugin/io/sto_file.hpp"

namespace flatsos::plugin {

/// signal extended by pad_count samples at each end, each the point reflection of a sample
/// through the end sample: before, 2 s[0] - s[k]; after, 2 s[n-1] - s[n-1-k], k = 1..pad_count.
/// Value and slope continue across the ends. Throws std::invalid_argument unless
/// 0 <= pad_count < signal.size().
std::vector<double> pad_by_point_reflection(const std::vector<double>& signal, int pad_count);

/// The smallest difference between consecutive times; throws for fewer than 2 times.
double smallest_time_step_s(const std::vector<double>& times_s);

/// first_s, first_s + step, ... (the step added repeatedly, as OpenSim does) while <= last_s.
std::vector<double> uniform_time_grid(double first_s, double last_s, double step_s);

/// First and last index of the samples OpenSim's tools report for [start_s, end_s]: for each
/// bound, the last sample at or before it (0 if none).
std::pair<std::size_t, std::size_t> report_sample_range(const std::vector<double>& times_s, double start_s,
                                                        double end_s);

struct ProcessedCoordinates {
  std::vector<double> sample_times_s;   ///< the splines' knots (the filtered grid)
  std::vector<double> report_times_s;   ///< the times InverseDynamicsTool reports
  std::vector<std::string> names;       ///< the table's columns, less "time"
  std::vector<NaturalQuinticSpline> splines;  ///< per name: rad (rotational) or m, in time (s)

  /// The spline of a coordinate; throws std::invalid_argument naming it when absent.
  const NaturalQuinticSpline& spline(const std::string& name) const;
};

using IsRotationalCoordinate = std::function<bool(const std::string& column)>;

/// Steps 1-6 above on a coordinates table whose first column is "time" (strictly increasing, at
/// least 6 rows). is_rotational names the columns that are angles (converted when
/// table.in_degrees); the others (translations, m) are left as they are. Throws
/// std::invalid_argument for a bad table or cutoff.
ProcessedCoordinates process_coordinates_like_opensim(const StoTable& table, double cutoff_hz,
                                                      const IsRotationalCoordinate& is_rotational);

/// Same, with the rotational columns named in a list.
ProcessedCoordinates process_coordinates_like_opensim(const StoTable& table, double cutoff_hz,
                                                      const std::vector<std::string>& rotational_columns);

}  // namespace flatsos::plugin
