#pragma once
// The excitation and activation bounds as rows over coefficients theta that move the tendon
// forces: at each time point and muscle four rows ">= 0" with exact gradients (through
// muscles::invert_muscle and muscles::excitation_bound_margins). Used by the SOS program's bounds
// (sos/), the free path (path/) and the receding-horizon step's period bounds (receding_horizon/),
// with the sequential LP of sequential_lp.hpp.

#include <array>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "flatsos/muscles/muscle_inverse.hpp"
#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/numerics/linear_program.hpp"

namespace flatsos::planner::detail {

/// a's lower bound per muscle: min_activation, or where that is 0 each muscle's activation floor.
Eigen::VectorXd activation_minima(const FlatOutputMap& flat, double min_activation);

/// Everything about one time point that does not depend on theta: the tendon-force jets are
/// F^(k) = base(:, k) + slope[k] * theta(columns), k = 0, 1, 2.
struct BoundPoint {
  double t_s = 0.0;
  Eigen::MatrixXd base;                 // m x 3
  std::vector<int> columns;             // theta entries that move Y's jet here
  std::array<Eigen::MatrixXd, 3> slope; // m x columns
  std::vector<muscles::SecondOrderJet> path; // per muscle
};

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
  double activation = 0.0, excitation = 0.0;  // the inverse's, when in_domain
  std::array<double, kRowsPerMuscle> value{};
  std::array<muscles::TendonForceJetGradient, kRowsPerMuscle> gradient{};     // in (F, dF, ddF)
  std::array<muscles::PathLengthJetGradient, kRowsPerMuscle> path_gradient{};  // in (L, dL, ddL)
};

/// The rows of one muscle from its tendon-force and path-length jets, with the gradients asked
/// for (path_gradient 0 unless the path's are).
MuscleBoundRows muscle_bound_rows(const muscles::MuscleParameters& p, const muscles::SecondOrderJet& force,
                                  const muscles::SecondOrderJet& path, double a_min, muscles::InverseGradients gradients,
                                  double margin = kBoundMargin);
/// The same with every gradient (true) or none.
MuscleBoundRows muscle_bound_rows(const muscles::MuscleParameters& p, const muscles::SecondOrderJet& force,
                                  const muscles::SecondOrderJet& path, double a_min, bool gradients,
                                  double margin = kBoundMargin);

/// Muscle j's tendon-force jet (F, dF/dt, d2F/dt2) at the point for theta.
muscles::SecondOrderJet point_force_jet(const BoundPoint& bp, int j, const Eigen::Ref<const Eigen::VectorXd>& theta);

/// The excitations and activations at the points for theta (points x m each): the muscles'
/// inverse from each point's force jets. False, leaving the outputs partly written, where a
/// muscle leaves its domain (no activation or excitation there).
bool point_excitations(const FlatOutputMap& flat, const std::vector<BoundPoint>& points, const Eigen::VectorXd& theta,
                       Eigen::MatrixXd& excitations, Eigen::MatrixXd& activations);

/// `margin`: how far inside the bounds the rows put a and n (kBoundMargin: the open-loop plans').
/// A point's path is fixed: the gradients are the force jet's alone (path_gradient stays 0).
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

/// The rows' Jacobian by rows, built from its triplets in O(nonzeros) whatever their order: the
/// step LPs take a few of its rows, and every row's norm and step are needed.
class JacobianByRow {
 public:
  JacobianByRow() = default;
  explicit JacobianByRow(const BoundRowsAt& rows);
  double l1(std::size_t row) const { return l1_[row]; }  ///< the row's l1 norm
  double dot(std::size_t row, const Eigen::VectorXd& d) const {
    double sum = 0.0;
    for (int k = start_[row]; k < start_[row + 1]; ++k) sum += value_[static_cast<std::size_t>(k)] * d[column_[static_cast<std::size_t>(k)]];
    return sum;
  }
  /// The row's entries as (lp_row, column, value) triplets.
  void append_row(std::size_t row, int lp_row, std::vector<Eigen::Triplet<double>>& entries) const;
  /// The row as a dense vector (into `out`, sized to the columns beforehand).
  void copy_row(std::size_t row, Eigen::Ref<Eigen::VectorXd> out) const;

 private:
  std::vector<int> start_, column_;
  std::vector<double> value_, l1_;  // l1_: each row's norm (every iteration's box test asks for it)
};

/// Sum of the reserve rows' violations (N) of the exchange LP in setup.lp.
double reserve_violation_N(const LinearProgram& lp, const Eigen::VectorXd& theta);

}  // namespace flatsos::planner::detail
