#pragma once
// The excitation and activation bounds as rows over the free coefficients theta of the flat
// outputs: at each time point and muscle four rows ">= 0" with exact gradients (through
// muscles::invert_muscle and muscles::excitation_bound_margins), and the same bounds checked on a
// dense grid through the inverse map.

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "flatsos/muscles/muscle_inverse.hpp"
#include "flatsos/planner/sos_program.hpp"
#include "sos/sos_setup.hpp"

namespace flatsos::planner::detail {

/// a's lower bound per muscle: the options' min_activation, or each muscle's activation floor.
Eigen::VectorXd activation_minima(const FlatOutputMap& flat, const ExcitationBoundsOptions& o);

/// Everything about one time point that does not depend on theta: the tendon-force jets are
/// F^(k) = base(:, k) + slope[k] * theta(columns), k = 0, 1, 2.
struct BoundPoint {
  double t_s = 0.0;
  Eigen::MatrixXd base;                 // m x 3
  std::vector<int> columns;             // theta entries that move Y's jet here
  std::array<Eigen::MatrixXd, 3> slope; // m x columns
  std::vector<muscles::SecondOrderJet> path; // per muscle
};

BoundPoint make_point(const SosSetup& setup, const MusclesAlongPath& mp, double t);
/// The flat outputs' part alone (base = C_Y times Y's particular jet; no torque, no path): for a
/// joint path that is itself a variable.
BoundPoint flat_output_point(const SosSetup& setup, const FlatOutputMap& flat, double t);

/// A row r >= 0 in units of activation, compressed where |r| > 1 to sign(r) (1 + ln|r|): the same
/// sign, so the same feasible set, and C1 (slope 1 at |r| = 1). A fibre stretched far along the
/// Gaussian force-length curve needs activations of 1e86 (rows and gradients that large made the
/// step LPs fail in Clp); compressed they are a few hundred with gradients of their size.
/// Inside the bounds (|r| <= 1) rows are unchanged.
struct CompressedRow {
  double value = 0.0, slope = 1.0;  // slope: d value / d r
};
CompressedRow compress_row(double r);

// The bound rows of one muscle at one point, each ">= 0": a - a_min, 1 - a, and the two margins
// of muscles::excitation_bound_margins for 0 <= n <= 1 (smooth in a and da/dt, defined where n
// is not), with their gradients in the point's tendon-force jet.
constexpr int kRowsPerMuscle = 4;
constexpr double kBoundMargin = 1e-6;
/// Outside the muscle's domain (slack tendon, collapsed fibre, no force capacity: no a, no n)
/// each row is -(kOutsideDomain + the inverse's domain_distance): more violated than any
/// compressed row inside can be (1 + ln(DBL_MAX) < 711), and less so toward the domain, so an
/// optimizer that starts or steps outside is led back in.
constexpr double kOutsideDomain = 1000.0;
struct MuscleBoundRows {
  bool in_domain = false;  // false: the rows are the extension above
  std::array<double, kRowsPerMuscle> value{};
  std::array<muscles::TendonForceJetGradient, kRowsPerMuscle> gradient{};     // in (F, dF, ddF)
  std::array<muscles::PathLengthJetGradient, kRowsPerMuscle> path_gradient{};  // in (L, dL, ddL)
};

/// The rows of one muscle from its tendon-force and path-length jets.
MuscleBoundRows muscle_bound_rows(const muscles::MuscleParameters& p, const muscles::SecondOrderJet& force,
                                  const muscles::SecondOrderJet& path, double a_min, bool gradients,
                                  double margin = kBoundMargin);

/// `margin`: how far inside the bounds the rows put a and n (kBoundMargin: the open-loop plans').
MuscleBoundRows bound_rows(const FlatOutputMap& flat, const BoundPoint& bp, int j, double a_min,
                           const Eigen::Ref<const Eigen::VectorXd>& theta, bool gradients, double margin = kBoundMargin);

// d(row)/d theta over the point's columns.
double column_derivative(const BoundPoint& bp, const muscles::TendonForceJetGradient& g, int j, std::size_t c);

/// The bound rows at every point (and their Jacobian) for theta.
struct BoundRowsAt {
  std::vector<double> value;  // per point, muscle, row
  std::vector<Eigen::Triplet<double>> jacobian;  // (row, theta column, derivative)
  double violation = 0.0;     // sum of max(0, -value)
};

BoundRowsAt evaluate_rows(const FlatOutputMap& flat, const std::vector<BoundPoint>& points, const Eigen::VectorXd& a_min,
                          const Eigen::VectorXd& theta, bool jacobian, double margin = kBoundMargin);
/// Appends the rows of points[first_point..] for theta to `rows` (numbered after its rows): the
/// rows of points added to an exchange, beside those of the points it had, at the same theta.
void append_rows(const FlatOutputMap& flat, const std::vector<BoundPoint>& points, std::size_t first_point,
                 const Eigen::VectorXd& a_min, const Eigen::VectorXd& theta, bool jacobian, double margin,
                 BoundRowsAt& rows);

/// Sum of the reserve rows' violations (N) of the exchange LP in setup.lp.
double reserve_violation_N(const LinearProgram& lp, const Eigen::VectorXd& theta);

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
