// process_motion: a measured motion (an OpenSim coordinates table, e.g. an inverse-kinematics
// .mot) padded, filtered and splined the way OpenSim's InverseDynamicsTool does it
// (plugin/io/motion_processing.hpp); writes q, qdot and qddot at the times the tool reports.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <iostream>

#include "example_support.hpp"
#include "flatsos/plugin/io/motion_processing.hpp"
#include "flatsos/plugin/io/sto_file.hpp"
#include "programs.hpp"

namespace flatsos::programs::process_motion {

namespace fp = flatsos::plugin;
namespace ex = flatsos::examples;

int run(int argc, char** argv) {
  CLI::App app{"OpenSim's inverse-dynamics preprocessing of a coordinates table.\n"
               "Pads each column by half its length (point reflection), resamples it on a uniform grid, low-pass "
               "filters it (3rd-order Butterworth, forward and backward), converts degrees to radians and fits a "
               "natural quintic spline; writes each coordinate's value, first and second derivative (columns NAME, "
               "NAME_u, NAME_udot; rad or m) at the times OpenSim's InverseDynamicsTool reports."};
  std::string input, out;
  double cutoff_hz = 6.0;
  std::vector<std::string> translational;
  std::vector<double> times_s;
  app.add_option("--coordinates", input, "coordinates table (.mot or .sto)")->required();
  app.add_option("--cutoff", cutoff_hz, "low-pass cutoff in Hz; negative: no filtering")->capture_default_str();
  app.add_option("--translational", translational, "a column in metres, not converted from degrees (repeat)");
  app.add_option("--at", times_s, "evaluate at these times (s) instead of the reported ones (repeat)");
  app.add_option("--out", out, "output .sto")->required();
  if (const int rc = ex::parse_arguments(app, argc, argv); rc >= 0) return rc;
  try {
    const fp::StoTable table = fp::read_sto(input);
    const auto processed = fp::process_coordinates_like_opensim(table, cutoff_hz, [&](const std::string& column) {
      return std::find(translational.begin(), translational.end(), column) == translational.end();
    });
    fp::StoTable result;
    result.name = "processed_coordinates";
    result.columns = {"time"};
    for (const auto& name : processed.names)
      for (const char* suffix : {"", "_u", "_udot"}) result.columns.push_back(name + suffix);
    if (times_s.empty()) times_s = processed.report_times_s;
    for (double t : times_s) {
      std::vector<double> row = {t};
      for (const auto& spline : processed.splines)
        for (int order = 0; order <= 2; ++order) row.push_back(spline.derivative(t, order));
      result.rows.push_back(std::move(row));
    }
    fp::write_sto(out, result);
    std::cout << "wrote " << result.rows.size() << " rows to " << out << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "process_motion: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace flatsos::programs::process_motion
