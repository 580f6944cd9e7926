#include "flatsos/plugin/io/motion_processing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "flatsos/plugin/io/butterworth_filter.hpp"

namespace flatsos::plugin {
namespace {

constexpr double kRadiansPerDegree = M_PI / 180.0;

void check_coordinates_table(const StoTable& table) {
  if (table.columns.empty() || table.columns.front() != "time")
    throw std::invalid_argument("coordinates table '" + table.name + "': the first column must be 'time'");
  if (table.rows.size() < 6)
    throw std::invalid_argument("coordinates table '" + table.name + "': needs at least 6 rows, has " +
                                std::to_string(table.rows.size()));
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    if (table.rows[r].size() != table.columns.size())
      throw std::invalid_argument("coordinates table '" + table.name + "': row " + std::to_string(r) +
                                  " has the wrong width");
    for (double v : table.rows[r])
      if (!std::isfinite(v))
        throw std::invalid_argument("coordinates table '" + table.name + "': row " + std::to_string(r) +
                                    " holds a value that is not finite");
    if (r > 0 && !(table.rows[r][0] > table.rows[r - 1][0]))
      throw std::invalid_argument("coordinates table '" + table.name + "': time must increase strictly (row " +
                                  std::to_string(r) + ")");
  }
}

std::vector<double> column_values(const StoTable& table, std::size_t c) {
  std::vector<double> out;
  out.reserve(table.rows.size());
  for (const auto& row : table.rows) out.push_back(row[c]);
  return out;
}

std::vector<double> spline_values_at(const NaturalQuinticSpline& spline, const std::vector<double>& times_s) {
  std::vector<double> out;
  out.reserve(times_s.size());
  for (double t : times_s) out.push_back(spline.value(t));
  return out;
}

// Steps 1-3: per column, the padded samples resampled on the grid and filtered.
std::vector<std::vector<double>> filtered_on_grid(const StoTable& table, double cutoff_hz,
                                                  std::vector<double>& grid_s) {
  const int pad_count = static_cast<int>(table.rows.size() / 2);
  const std::vector<double> padded_times_s = pad_by_point_reflection(column_values(table, 0), pad_count);
  const double step_s = smallest_time_step_s(padded_times_s);
  grid_s = uniform_time_grid(padded_times_s.front(), padded_times_s.back(), step_s);
  std::vector<std::vector<double>> columns;
  for (std::size_t c = 1; c < table.columns.size(); ++c) {
    const NaturalQuinticSpline padded(padded_times_s, pad_by_point_reflection(column_values(table, c), pad_count));
    columns.push_back(lowpass_forward_backward(spline_values_at(padded, grid_s), cutoff_hz, step_s));
  }
  return columns;
}

}  // namespace

std::vector<double> pad_by_point_reflection(const std::vector<double>& signal, int pad_count) {
  const int n = static_cast<int>(signal.size());
  if (pad_count < 0 || pad_count >= n)
    throw std::invalid_argument("pad_by_point_reflection: pad_count must lie in [0, " + std::to_string(n - 1) +
                                "] for " + std::to_string(n) + " samples, got " + std::to_string(pad_count));
  std::vector<double> out;
  out.reserve(static_cast<std::size_t>(n + 2 * pad_count));
  for (int k = pad_count; k >= 1; --k) out.push_back(2.0 * signal.front() - signal[static_cast<std::size_t>(k)]);
  out.insert(out.end(), signal.begin(), signal.end());
  for (int k = 1; k <= pad_count; ++k)
    out.push_back(2.0 * signal.back() - signal[static_cast<std::size_t>(n - 1 - k)]);
  return out;
}

double smallest_time_step_s(const std::vector<double>& times_s) {
  if (times_s.size() < 2) throw std::invalid_argument("smallest_time_step_s: needs at least 2 times");
  double smallest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < times_s.size(); ++i) smallest = std::min(smallest, times_s[i] - times_s[i - 1]);
  return smallest;
}

std::vector<double> uniform_time_grid(double first_s, double last_s, double step_s) {
  if (!(step_s > 0.0) || !std::isfinite(first_s) || !std::isfinite(last_s) || !std::isfinite(step_s))
    throw std::invalid_argument("uniform_time_grid: needs finite bounds and a positive finite step_s");
  if ((last_s - first_s) / step_s > 1e7)
    throw std::invalid_argument("uniform_time_grid: more than 1e7 samples requested");
  std::vector<double> grid;
  for (double t = first_s; t <= last_s; t += step_s) grid.push_back(t);
  return grid;
}

std::pair<std::size_t, std::size_t> report_sample_range(const std::vector<double>& times_s, double start_s,
                                                        double end_s) {
  if (times_s.empty()) throw std::invalid_argument("report_sample_range: no samples");
  auto last_at_or_before = [&](double t) {
    const auto after = std::upper_bound(times_s.begin(), times_s.end(), t);
    return after == times_s.begin() ? std::size_t{0} : static_cast<std::size_t>(after - times_s.begin()) - 1;
  };
  return {last_at_or_before(start_s), last_at_or_before(end_s)};
}

const NaturalQuinticSpline& ProcessedCoordinates::spline(const std::string& name) const {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return splines[i];
  throw std::invalid_argument("processed coordinates have no column '" + name + "'");
}

ProcessedCoordinates process_coordinates_like_opensim(const StoTable& table, double cutoff_hz,
                                                      const IsRotationalCoordinate& is_rotational) {
  check_coordinates_table(table);
  if (std::isnan(cutoff_hz)) throw std::invalid_argument("process_coordinates_like_opensim: cutoff_hz is NaN");
  ProcessedCoordinates out;
  std::vector<std::vector<double>> columns;
  const std::vector<double> table_times_s = column_values(table, 0);
  if (cutoff_hz >= 0.0) {
    columns = filtered_on_grid(table, cutoff_hz, out.sample_times_s);
  } else {
    out.sample_times_s = table_times_s;
    for (std::size_t c = 1; c < table.columns.size(); ++c) columns.push_back(column_values(table, c));
  }
  for (std::size_t c = 1; c < table.columns.size(); ++c) {
    std::vector<double>& values = columns[c - 1];
    if (table.in_degrees && is_rotational && is_rotational(table.columns[c]))
      for (double& v : values) v *= kRadiansPerDegree;
    out.names.push_back(table.columns[c]);
    out.splines.emplace_back(out.sample_times_s, values);
  }
  const std::vector<double>& grid = out.sample_times_s;
  const auto [first, last] = report_sample_range(grid, std::max(grid.front(), table_times_s.front()),
                                                 std::min(grid.back(), table_times_s.back()));
  out.report_times_s.assign(grid.begin() + static_cast<std::ptrdiff_t>(first),
                            grid.begin() + static_cast<std::ptrdiff_t>(last) + 1);
  return out;
}

ProcessedCoordinates process_coordinates_like_opensim(const StoTable& table, double cutoff_hz,
                                                      const std::vector<std::string>& rotational_columns) {
  return process_coordinates_like_opensim(table, cutoff_hz, [&rotational_columns](const std::string& column) {
    return std::find(rotational_columns.begin(), rotational_columns.end(), column) != rotational_columns.end();
  });
}

}  // namespace flatsos::plugin
