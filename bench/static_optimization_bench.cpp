#include "static_optimization_bench.hpp"

#include <memory>
#include <string>

#include "flatsos/planner/static_optimization.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"
#include "flatsos/plugin/io/sto_file.hpp"
#include "default_model.hpp"
#include "timing.hpp"

namespace flatsos::bench {

nlohmann::json static_optimization_timing(int repetitions) {
  const std::string arm26 = examples::default_model_path("opensim/arm26/");
  const auto motion = plugin::process_coordinates_like_opensim(
      plugin::read_sto(arm26 + "inverse_kinematics/arm26_InverseKinematics.mot"), 6.0,
      std::vector<std::string>{"r_shoulder_elev", "r_elbow_flex"});
  const double seconds_of_motion = motion.report_times_s.back() - motion.report_times_s.front();
  nlohmann::json out = {{"model", "arm26.osim, OpenSim 2.x's muscles"},
                        {"frames", motion.report_times_s.size()},
                        {"seconds_of_motion", seconds_of_motion}};
  for (const bool geometry : {true, false}) {
    const auto model = std::make_shared<const plugin::MusculoskeletalModel>(
        plugin::import_opensim_file(arm26 + "arm26.osim", geometry, true).model);
    planner::StaticOptimizationResult r;
    const std::vector<double> t = repeat(repetitions, [&] { r = planner::static_optimization(*model, motion); });
    const double median_s = examples::median(t);
    out[geometry ? "geometry_paths" : "fitted_paths"] = {
        {"whole_motion", stats(t, 1e3, "ms")},
        {"per_frame_us", 1e6 * median_s / static_cast<double>(r.time_s.size())},
        {"real_time_factor", seconds_of_motion / median_s},
        {"success", r.success()}};
  }
  return out;
}

}  // namespace flatsos::bench
