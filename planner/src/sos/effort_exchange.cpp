#include "sos/effort_exchange.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <boost/math/quadrature/gauss.hpp>

#include "bounds/effort_model.hpp"
#include "bounds/sequential_lp.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "numerics/dense_qp.hpp"
#include "sos/bound_points.hpp"

namespace flatsos::planner::detail {

namespace {

constexpr int kMaxIterations = 200;  // QP steps over all rounds
constexpr int kMaxHalvings = 30;
// Stops once the QP predicts a decrease below this fraction of the effort.
constexpr double kRelativeDecrease = 1e-10;
// A trial theta counts as inside a bound row while the row keeps half its margin.
constexpr double kBoundRowTolerance = 0.5 * kBoundMargin;

// The segments' ends: the torque pieces refined by the spline's spans (every constraint
// polynomial lives on one segment).
std::vector<double> segment_ends(const SosSetup& setup) {
  std::vector<double> ends{0.0, setup.duration_s};
  for (const ConstraintPolynomial& c : setup.constraints) ends.push_back(c.t0_s), ends.push_back(c.t1_s);
  std::sort(ends.begin(), ends.end());
  ends.erase(std::unique(ends.begin(), ends.end(), [](double a, double b) { return b - a < 1e-12; }), ends.end());
  return ends;
}

// The effort's quadrature: kEffortGaussPoints Gauss-Legendre points per segment.
std::vector<BoundPoint> quadrature_points(const SosSetup& setup, const MusclesAlongPath& mp, std::vector<double>& weights_s) {
  using Rule = boost::math::quadrature::gauss<double, kEffortGaussPoints>;
  const std::vector<double> ends = segment_ends(setup);
  std::vector<BoundPoint> points;
  weights_s.clear();
  for (std::size_t k = 0; k + 1 < ends.size(); ++k) {
    const double mid = 0.5 * (ends[k] + ends[k + 1]), half = 0.5 * (ends[k + 1] - ends[k]);
    // Boost's rule keeps the non-negative abscissae; each but 0 stands for a pair +-x.
    for (std::size_t i = 0; i < Rule::abscissa().size(); ++i) {
      const double x = Rule::abscissa()[i], w = Rule::weights()[i];
      for (const double sign : {-1.0, 1.0}) {
        if (x == 0.0 && sign > 0.0) continue;
        points.push_back(make_point(setup, mp, mid + sign * half * x));
        weights_s.push_back(half * w);
      }
    }
  }
  return points;
}

// One minimize_effort_by_exchange call.
class EffortExchange {
 public:
  EffortExchange(SosSetup& setup, const MusclesAlongPath& mp, const SosSettings& o, const Effort& effort,
                 Eigen::VectorXd& theta, SosProgramResult& result)
      : setup_(setup), mp_(mp), flat_(mp.flat), o_(o), effort_(effort), theta_(theta), result_(result),
        a_min_(activation_minima(mp.flat, o.bounds.min_activation)) {}

  bool run() {
    effort_points_ = quadrature_points(setup_, mp_, weights_s_);
    if (o_.bounds.enforce) {
      jets_ = torque_jets_on_grid(flat_, mp_.workspace, mp_.path, gridStep(), o_.bounds.check_points);
      addBoundPoint(0.0);
      for (double t : setup_.basis.pointsPerSpan(o_.bounds.initial_points_per_span)) addBoundPoint(t);
      addBoundPoint(setup_.duration_s);
    }
    if (!evaluate_effort(flat_, effort_, effort_points_, weights_s_, theta_, true, model_, true))
      return fail("the effort '" + effort_.name() + "' is not defined at the linear effort's plan");
    for (int round = 0; round < o_.bounds.max_rounds + o_.max_exchange_rounds; ++round) {
      result_.effort_rounds = round + 1;
      result_.lp_points = build_exchange_rows(setup_, o_.feasibility_margin_N);
      if (!descend()) return false;
      if (!addViolations()) return finish();
    }
    return fail("the effort's exchange did not converge in " + std::to_string(result_.effort_rounds) + " rounds");
  }

 private:
  double gridStep() const { return setup_.duration_s / (o_.bounds.check_points - 1); }

  void addBoundPoint(double t) {
    for (const BoundPoint& bp : bound_points_)
      if (std::abs(bp.t_s - t) < 1e-9) return;
    bound_points_.push_back(make_point(setup_, mp_, t));
  }

  // How far theta leaves the rows: reserve rows in N over the largest bound, bound rows in
  // activation units, each beyond its tolerance (0: inside every row).
  double violation(const Eigen::VectorXd& theta) const {
    const LinearProgram& lp = setup_.lp;
    const double scale = 1.0 + lp.row_lower.cwiseAbs().maxCoeff();
    double v = (lp.row_lower - lp.G * theta - Eigen::VectorXd::Constant(lp.G.rows(), 0.5 * o_.feasibility_margin_N))
            .cwiseMax(0.0).sum() / scale;
    if (!bound_points_.empty())
      for (const double r : evaluate_rows(flat_, bound_points_, a_min_, theta, false).value)
        v += std::max(0.0, -r - kBoundRowTolerance);
    return v;
  }

  // The QP's rows J d >= lower: the bound rows linearized at theta (a violated one asked to
  // clear, one theta does not move only not to get worse), the reserve rows, the box.
  void qpRows(Eigen::MatrixXd& J, Eigen::VectorXd& lower) {
    const LinearProgram& lp = setup_.lp;
    const Eigen::Index n = theta_.size(), reserves = lp.G.rows();
    BoundRowsAt& at = rows_at_theta_;
    at = BoundRowsAt{};
    if (!bound_points_.empty()) at = evaluate_rows(flat_, bound_points_, a_min_, theta_, true);
    const auto bound_rows = static_cast<Eigen::Index>(at.value.size());
    J.setZero(bound_rows + reserves + 2 * n, n);
    lower.resize(J.rows());
    place_linearized_bound_rows(at, J, lower);
    J.middleRows(bound_rows, reserves) = lp.G;
    lower.segment(bound_rows, reserves) = lp.row_lower - lp.G * theta_;
    J.block(bound_rows + reserves, 0, n, n).setIdentity();
    lower.segment(bound_rows + reserves, n) = lp.x_lower - theta_;
    J.bottomRows(n) = -Eigen::MatrixXd::Identity(n, n);
    lower.tail(n) = theta_ - lp.x_upper;
  }

  // QP steps at these rows until the effort's decrease is negligible inside them. False with a
  // message when the rows cannot be reached or a QP fails.
  bool descend() {
    double current = violation(theta_);
    Eigen::MatrixXd J, H;
    Eigen::VectorXd lower, d;
    std::vector<int> hint;  // the last QP's active rows (the rows keep their indices in a round)
    while (result_.effort_iterations < kMaxIterations) {
      qpRows(J, lower);
      // Levenberg's shift keeps the model strictly convex where the effort is flat in a direction.
      H = model_.hessian;
      H.diagonal().array() += 1e-9 * std::max(H.diagonal().maxCoeff(), 1e-12);
      const DenseQpResult r = solve_dense_qp(H, model_.gradient, J, lower, qp_, d, nullptr, 1e-10, &hint);
      hint = qp_.active;
      if (!r.solved) return fail("the effort's QP was not solved: " + r.failure);
      ++result_.effort_iterations;
      if (current == 0.0 && !(predictedDecrease(d) < -kRelativeDecrease * (1e-12 + std::abs(model_.value)))) return true;
      // A full step inside the rows' linearization that leaves the curved rows: first the same QP
      // with the rows' curvature along it taken in (a second-order correction, Nocedal and
      // Wright 2006, section 18.3), then shorter steps.
      bool accepted = false;
      Eigen::VectorXd corrected = d;
      if (current == 0.0 && violation(theta_ + d) > 0.0 && correctedStep(H, J, lower, corrected, hint))
        accepted = lineSearch(corrected, current);
      if (!accepted) accepted = lineSearch(d, current);
      if (!accepted) {
        if (current == 0.0) return true;  // no decrease along the QP's step: as low as the model sees
        return fail("the effort's sequential QP could not return inside the reserves and bounds (violation " +
                    std::to_string(current) + ")");
      }
      if (!evaluate_effort(flat_, effort_, effort_points_, weights_s_, theta_, true, model_, true))
        return fail("the effort could not be differentiated at an accepted step");
    }
    return fail("the effort's sequential QP did not converge in " + std::to_string(kMaxIterations) + " steps");
  }

  double predictedDecrease(const Eigen::VectorXd& d) const {
    return model_.gradient.dot(d) + 0.5 * d.dot(model_.hessian * d);
  }

  // Halvings of d: inside the rows a step must keep them and lower the effort (Armijo);
  // outside, come closer. On success theta and `current` move.
  bool lineSearch(const Eigen::VectorXd& d, double& current) {
    const double predicted = predictedDecrease(d);
    EffortModel trial;
    double s = 1.0;
    for (int k = 0; k < kMaxHalvings; ++k, s *= 0.5) {
      const Eigen::VectorXd trial_theta = theta_ + s * d;
      const double trial_violation = violation(trial_theta);
      if ((current == 0.0 ? trial_violation == 0.0 : trial_violation < current) &&
          evaluate_effort(flat_, effort_, effort_points_, weights_s_, trial_theta, false, trial, true) &&
          (current > 0.0 || trial.value <= model_.value + 1e-4 * s * predicted)) {
        theta_ = trial_theta, current = trial_violation;
        return true;
      }
    }
    return false;
  }

  // d solved again with each bound row's lower bound moved by how far the row at theta + d
  // differs from its linearization. False when there are no bound rows or the QP fails.
  bool correctedStep(const Eigen::MatrixXd& H, const Eigen::MatrixXd& J, const Eigen::VectorXd& lower,
                     Eigen::VectorXd& d, std::vector<int>& hint) {
    const std::vector<double>& before = rows_at_theta_.value;
    if (before.empty()) return false;
    const std::vector<double> after = evaluate_rows(flat_, bound_points_, a_min_, theta_ + d, false).value;
    Eigen::VectorXd corrected = lower;
    for (std::size_t i = 0; i < before.size(); ++i) {
      const auto row = static_cast<Eigen::Index>(i);
      if (J.row(row).cwiseAbs().maxCoeff() > 1e-12) corrected[row] -= after[i] - before[i] - J.row(row).dot(d);
    }
    Eigen::VectorXd step;
    if (!solve_dense_qp(H, model_.gradient, J, corrected, qp_, step, nullptr, 1e-10, &hint).solved) return false;
    hint = qp_.active;
    d = step;
    return true;
  }

  // The reserves' exact minima and the bounds on the check grid at theta: violations join as
  // points. Returns whether any did.
  bool addViolations() {
    double min_reserve = 0.0;
    bool added = add_violated_points(setup_, theta_, o_.feasibility_margin_N, min_reserve, kConstraintTolerance_N,
                                     kLiftBelow_N);
    result_.min_constraint_value_N = min_reserve;
    if (!o_.bounds.enforce) return added;
    const GridExcess excess = grid_excess(setup_, mp_, jets_, a_min_, theta_, o_.bounds.check_points);
    result_.max_bound_excess = excess.worst;
    const std::size_t before = bound_points_.size();
    for (double t : violated_times(excess, gridStep(), 0.0)) addBoundPoint(t);
    result_.bound_points = static_cast<int>(bound_points_.size());
    return added || (excess.worst > o_.bounds.tolerance && bound_points_.size() > before);
  }

  bool finish() {
    if (o_.bounds.enforce && result_.max_bound_excess > o_.bounds.tolerance)
      return fail("the effort's optimum leaves the bounds by " + std::to_string(result_.max_bound_excess) +
                  " at points already imposed");
    result_.effort_value = model_.value;
    return true;
  }

  bool fail(const std::string& why) {
    result_.status = SolveStatus::Failed;
    result_.message = "minimizing '" + effort_.name() + "': " + why;
    return false;
  }

  SosSetup& setup_;
  const MusclesAlongPath& mp_;
  const FlatOutputMap& flat_;
  const SosSettings& o_;
  const Effort& effort_;
  Eigen::VectorXd& theta_;
  SosProgramResult& result_;
  const Eigen::VectorXd a_min_;
  std::vector<BoundPoint> effort_points_, bound_points_;
  std::vector<double> weights_s_;
  std::vector<TorqueJet> jets_;
  EffortModel model_;
  BoundRowsAt rows_at_theta_;  // the bound rows at theta, as the last QP linearized them
  DenseQpWorkspace qp_;
};

}  // namespace

bool minimize_effort_by_exchange(SosSetup& setup, const MusclesAlongPath& muscles, const SosSettings& options,
                                 const Effort& effort, Eigen::VectorXd& theta, SosProgramResult& result) {
  const Stopwatch wall;
  result.effort_name = effort.name();
  result.effort_unit = effort.unit();
  const bool solved = EffortExchange(setup, muscles, options, effort, theta, result).run();
  result.effort_seconds = wall.seconds();
  return solved;
}

}  // namespace flatsos::planner::detail
