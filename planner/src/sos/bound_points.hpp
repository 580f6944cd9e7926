#pragma once
// The bound rows' time points of the SOS program (bounds/bound_rows.hpp) and the bounds checked on
// a dense grid through the inverse map, for the flat outputs of theta.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "bounds/bound_rows.hpp"
#include "sos/sos_setup.hpp"

namespace flatsos::planner::detail {

BoundPoint make_point(const SosSetup& setup, const MusclesAlongPath& mp, double t);
/// The flat outputs' part alone (base = C_Y times Y's particular jet; no torque, no path): for a
/// joint path that is itself a variable.
BoundPoint flat_output_point(const SosSetup& setup, const FlatOutputMap& flat, double t);

// The bounds on the check grid for the flat outputs of theta: per grid time the largest excess
// over any muscle's bounds (0 inside; +inf where the inverse is undefined), and the worst one.
// With a stride, every stride-th time of the grid only (the excess then has one entry per time
// visited; `points - 1` must be a multiple of the stride).
//
// With stride 1 the check also looks between the grid's points: the muscle inverse turns smooth
// force jets into sharp excitation features (during a fast throw n dipped to -1.5e-4 between
// points 1 ms apart that all held n >= 0), and a simulator clamps such a dip. Every local
// maximum of a muscle's signed excess within kNearBound of its bounds is maximized over its two
// neighbouring intervals (Brent's method); maxima above the tolerance count as violations at
// their own times. The signed excess is the rows' (uncompressed, without the margin): in
// activation units, and it sees the fastest possible deactivation, which n does not.
constexpr double kNearBound = 1e-2;  // which grid maxima are searched between points
struct GridExcess {
  std::vector<double> excess;
  double worst = 0.0;
  std::string worst_text;
  int stride = 1;
  struct BetweenPoints {
    double t_s = 0.0, excess = 0.0;
  };
  std::vector<BetweenPoints> between;  // maxima between the points, above 0 (stride 1 only)
};

GridExcess grid_excess(const SosSetup& setup, const MusclesAlongPath& mp, const std::vector<TorqueJet>& jets,
                       const Eigen::VectorXd& a_min, const Eigen::VectorXd& theta, int points, int stride = 1);

// Grid times where the excess is a local maximum above the tolerance (h: the full grid's
// spacing), then the times of the maxima between points above it.
std::vector<double> violated_times(const GridExcess& g, double h, double tolerance);

}  // namespace flatsos::planner::detail
