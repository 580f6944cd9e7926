#include "sos/effort_exchange.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <boost/math/quadrature/gauss.hpp>

#include "bounds/effort_sqp.hpp"
#include "bounds/sequential_lp.hpp"
#include "flatsos/plugin/stopwatch.hpp"
#include "sos/bound_points.hpp"

namespace flatsos::planner::detail {

namespace {

constexpr int kMaxIterations = 200;  // QP steps over all rounds

// The segments' ends: the torque pieces refined by the spline's spans (every constraint
// polynomial lives on one segment).
std::vector<double> segment_ends(const SosSetup& setup) {
  std::vector<double> ends{0.0, setup.duration_s};
  for (const ConstraintPolynomial& c : setup.constraints) ends.push_back(c.t0_s), ends.push_back(c.t1_s);
  return ends;
}

// The effort's points on the program's segments, with their weights.
std::vector<BoundPoint> quadrature_points(const SosSetup& setup, const MusclesAlongPath& mp, std::vector<double>& weights_s) {
  const EffortQuadrature q = effort_quadrature(segment_ends(setup));
  std::vector<BoundPoint> points;
  for (double t : q.times_s) points.push_back(make_point(setup, mp, t));
  weights_s = q.weights_s;
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
    if (!sqp_.start(theta_)) return fail("the effort '" + effort_.name() + "' is not defined at the linear effort's plan");
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

  // QP steps at these rows until the effort's decrease is negligible inside them.
  bool descend() {
    if (sqp_.descend(theta_, result_.effort_iterations, kMaxIterations)) return true;
    return fail(sqp_.failure());
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
    result_.effort_value = sqp_.model().value;
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
  const EffortSqpProblem problem_{flat_, effort_, effort_points_, weights_s_, setup_.lp,
                                  0.5 * o_.feasibility_margin_N, bound_points_, a_min_};
  EffortSqp sqp_{problem_};
};

}  // namespace

EffortQuadrature effort_quadrature(std::vector<double> ends) {
  using Rule = boost::math::quadrature::gauss<double, kEffortGaussPoints>;
  std::sort(ends.begin(), ends.end());
  ends.erase(std::unique(ends.begin(), ends.end(), [](double a, double b) { return b - a < 1e-12; }), ends.end());
  EffortQuadrature out;
  for (std::size_t k = 0; k + 1 < ends.size(); ++k) {
    const double mid = 0.5 * (ends[k] + ends[k + 1]), half = 0.5 * (ends[k + 1] - ends[k]);
    // Boost's rule keeps the non-negative abscissae; each but 0 stands for a pair +-x.
    for (std::size_t i = 0; i < Rule::abscissa().size(); ++i) {
      const double x = Rule::abscissa()[i], w = Rule::weights()[i];
      for (const double sign : {-1.0, 1.0}) {
        if (x == 0.0 && sign > 0.0) continue;
        out.times_s.push_back(mid + sign * half * x);
        out.weights_s.push_back(half * w);
      }
    }
  }
  return out;
}

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
