#pragma once
// The bound rows of fixed points (bound_rows.hpp) for Newton's method on an active set: each row's
// gradient is kept in its point's tendon-force jet (three numbers) and turned into theta's only
// where asked (the active rows, a joining row), and a step's change of every row comes from
// each point's force jets along it. The receding horizon's evaluations then skip the Jacobian
// in theta (on the leg 65 000 entries over 1760 rows, most of an evaluation's cost).

#include <vector>

#include "bounds/active_set_newton.hpp"

namespace flatsos::planner::detail {

class PointRows final : public ActiveSetRows {
 public:
  /// Keeps references to `flat` and `points`.
  PointRows(const FlatOutputMap& flat, const std::vector<BoundPoint>& points, Eigen::VectorXd a_min, double margin);
  void evaluate(const Eigen::VectorXd& x, bool gradients) override;
  const std::vector<double>& values() const override { return value_; }
  void gradient(std::size_t row, Eigen::Ref<Eigen::VectorXd> out) const override;
  void change(const Eigen::VectorXd& d, std::vector<double>& out) const override;
  void curvature(const std::vector<int>& rows, const Eigen::VectorXd& weight, const Eigen::VectorXd& z,
                 Eigen::VectorXd& out) const override;
  double violation() const { return violation_; }  ///< sum of max(0, -row)
  /// The last evaluation's excitations and activations (points x m each), as point_excitations
  /// gives them, when it was at x and every muscle had an inverse at every point; else false.
  bool inverseAt(const Eigen::VectorXd& x, Eigen::MatrixXd& excitations, Eigen::MatrixXd& activations) const;

 private:
  void requireGradients() const;  // throws std::logic_error after an evaluation without them
  const FlatOutputMap& flat_;
  const std::vector<BoundPoint>& points_;
  Eigen::VectorXd a_min_;
  double margin_;
  Eigen::VectorXd x_;  // the last evaluation's
  std::vector<double> value_;
  std::vector<muscles::TendonForceJetGradient> gradient_;  // per row, in its point's (F, dF, ddF)
  std::vector<double> activation_, excitation_;           // per point and muscle
  bool every_inverse_ = false;                            // every muscle in its domain, n finite
  double violation_ = 0.0;
};

}  // namespace flatsos::planner::detail
