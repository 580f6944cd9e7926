#pragma once
// Settling times computed as a closed loop reports its rows, so that a run of any length needs
// no table: what plugin::settling_time finds in a state table, window by window.

#include <Eigen/Core>
#include <vector>

#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace flatsos::planner::detail {

class SettlingTracker {
 public:
  /// Windows [starts[i], starts[i + 1]) (the last one open), each with its target; a pin is
  /// inside within tolerance_rad of its target, a slider within slider_tolerance_m.
  SettlingTracker(const plugin::MusculoskeletalModel& model, std::vector<double> starts,
                  std::vector<Eigen::VectorXd> targets, double tolerance_rad,
                  double slider_tolerance_m);
  /// The next row (times ascending). Allocates nothing.
  void observe(const SimTK::State& state);
  /// Per window that had begun by the last row: when the joints came inside and stayed there up
  /// to the window's last row (absolute time; -1: never, or no row in the window).
  std::vector<double> settledTimes() const;

 private:
  void closeWindowsBefore(double t);
  const plugin::MusculoskeletalModel& model_;
  std::vector<double> starts_;
  std::vector<Eigen::VectorXd> targets_;
  double tolerance_rad_, slider_tolerance_m_;
  std::vector<double> settled_;  ///< per window closed so far
  std::size_t window_ = 0;       ///< the current window
  bool inside_ = false;          ///< the last row was inside
  double inside_since_ = 0.0;    ///< the first row of the streak inside that the last row ends
  bool any_row_ = false;
  Eigen::VectorXd q_rad_;
};

}  // namespace flatsos::planner::detail
