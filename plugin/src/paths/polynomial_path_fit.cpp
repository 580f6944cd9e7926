// Polynomial paths fitted to geometry (polynomial_path_fit.hpp): samples, the least-squares
// system of lengths and moment arms (OpenSim's PolynomialPathFitter::fitAllCoefficients in
// structure: the moment-arm rows are minus the terms' partial derivatives), the order search
// and the check between the samples.

#include "flatsos/plugin/paths/polynomial_path_fit.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "flatsos/muscles/length_polynomial.hpp"
#include "flatsos/plugin/paths/path_evaluation.hpp"

namespace flatsos::plugin {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using muscles::LengthPolynomial;

[[noreturn]] void fail(const std::string& what) { throw OpenSimModelError("path fit: " + what); }

void check_options(const OpenSimModel& model, const PathFitOptions& options) {
  for (const auto& [name, range] : options.ranges) {
    if (!model.coordinate(name)) fail("ranges: the model has no coordinate '" + name + "'");
    if (!(std::isfinite(range[0]) && std::isfinite(range[1]) && range[0] < range[1]))
      fail("ranges['" + name + "']: the range must be finite with low < high");
  }
  for (const auto& held : options.held)
    if (!model.coordinate(held.first)) fail("held: the model has no coordinate '" + held.first + "'");
  if (!(0 <= options.min_order && options.min_order <= options.max_order && options.max_order <= 12))
    fail("orders: need 0 <= min_order <= max_order <= 12");
  if (!(options.length_tolerance_m > 0 && options.moment_arm_tolerance_m > 0)) fail("tolerances must be positive");
  if (options.max_samples < 2) fail("max_samples must be at least 2");
}

// The i-th element (from 1) of the Halton sequence in `base`, in (0, 1).
double halton(long i, int base) {
  double f = 1.0, r = 0.0;
  for (; i > 0; i /= base) {
    f /= base;
    r += f * static_cast<double>(i % base);
  }
  return r;
}

// Unit-cube postures: the fitting samples and the check postures between them. A grid with its
// ends for up to three coordinates (the check at the cells' centres); a Halton sequence beyond.
void unit_samples(int dimension, int max_samples, std::vector<VectorXd>& fit, std::vector<VectorXd>& check) {
  fit.clear();
  check.clear();
  if (dimension <= 3) {
    int n = static_cast<int>(std::floor(std::pow(static_cast<double>(max_samples), 1.0 / dimension) + 1e-9));
    n = std::clamp(n, 2, 201);
    auto grid = [&](int points, double offset, double step, std::vector<VectorXd>& out) {
      long total = 1;
      for (int k = 0; k < dimension; ++k) total *= points;
      for (long index = 0; index < total; ++index) {
        VectorXd x(dimension);
        long rest = index;
        for (int k = 0; k < dimension; ++k, rest /= points) x[k] = offset + step * static_cast<double>(rest % points);
        out.push_back(x);
      }
    };
    const double step = 1.0 / (n - 1);
    grid(n, 0.0, step, fit);
    grid(n - 1, 0.5 * step, step, check);
    return;
  }
  static constexpr int kPrimes[] = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53};
  for (long i = 1; i <= 2L * max_samples; ++i) {
    VectorXd x(dimension);
    for (int k = 0; k < dimension; ++k) x[k] = halton(i, kPrimes[k]);
    (i <= max_samples ? fit : check).push_back(x);
  }
}

// What the geometry gives at a set of postures: lengths and moment arms (one column per
// fitted coordinate), and the postures in the fitted coordinates.
struct Samples {
  MatrixXd x;          // postures x arguments
  VectorXd length;     // m
  MatrixXd moment_arm; // postures x arguments, m (or 1 for a translation)
};

class PathSampler {
 public:
  PathSampler(const OpenSimModel& model, const PathFitOptions& options, const GeometryPathEvaluator& path,
              std::vector<std::string> arguments)
      : model_(model), options_(options), path_(path), arguments_(std::move(arguments)) {}

  Samples sample(const std::vector<VectorXd>& unit) const {
    const int d = static_cast<int>(arguments_.size());
    Samples s{MatrixXd(unit.size(), d), VectorXd(unit.size()), MatrixXd(unit.size(), d)};
    for (std::size_t i = 0; i < unit.size(); ++i) {
      for (int k = 0; k < d; ++k) {
        const auto& range = options_.ranges.at(arguments_[k]);
        s.x(i, k) = range[0] + unit[i][k] * (range[1] - range[0]);
      }
      const OpenSimCoordinateValues q = posture(s.x.row(i).transpose());
      s.length[i] = path_.length(q);
      for (int k = 0; k < d; ++k) s.moment_arm(i, k) = path_.momentArm(q, arguments_[k]);
      if (!std::isfinite(s.length[i]) || !s.moment_arm.row(i).allFinite())
        fail("muscle '" + path_.muscle() + "': the geometry gives a length or moment arm that is not finite at a sample");
    }
    return s;
  }

 private:
  OpenSimCoordinateValues posture(const VectorXd& x) const {
    OpenSimCoordinateValues q;
    for (const OpenSimCoordinate& c : model_.coordinates) {
      const auto held = options_.held.find(c.name);
      q[c.name] = held == options_.held.end() ? 0.0 : held->second;
    }
    for (std::size_t k = 0; k < arguments_.size(); ++k) q[arguments_[k]] = x[static_cast<int>(k)];
    for (const OpenSimCoupler& coupler : model_.couplers)
      if (!options_.held.count(coupler.dependent))
        q[coupler.dependent] = coupler.scale * coupler.function.value(q.at(coupler.independent));
    return q;
  }

  const OpenSimModel& model_;
  const PathFitOptions& options_;
  const GeometryPathEvaluator& path_;
  std::vector<std::string> arguments_;
};

// The least-squares system's rows at the samples: the terms (lengths), then minus the terms'
// partial derivatives in each argument (moment arms), one block of rows per argument.
MatrixXd design_matrix(const MatrixXd& x, int order) {
  const int n = static_cast<int>(x.rows()), d = static_cast<int>(x.cols());
  const std::vector<std::vector<int>> exponents = LengthPolynomial::termExponents(d, order);
  MatrixXd A = MatrixXd::Zero(n * (d + 1), static_cast<int>(exponents.size()));
  for (int i = 0; i < n; ++i) {
    for (std::size_t t = 0; t < exponents.size(); ++t) {
      double term = 1.0;
      for (int k = 0; k < d; ++k) term *= std::pow(x(i, k), exponents[t][k]);
      A(i, static_cast<int>(t)) = term;
      for (int m = 0; m < d; ++m) {
        if (exponents[t][m] == 0) continue;
        double partial = exponents[t][m];
        for (int k = 0; k < d; ++k) partial *= std::pow(x(i, k), exponents[t][k] - (k == m ? 1 : 0));
        A((m + 1) * n + i, static_cast<int>(t)) = -partial;
      }
    }
  }
  return A;
}

VectorXd targets(const Samples& s) {
  const int n = static_cast<int>(s.length.size()), d = static_cast<int>(s.x.cols());
  VectorXd b(n * (d + 1));
  b.head(n) = s.length;
  for (int m = 0; m < d; ++m) b.segment((m + 1) * n, n) = s.moment_arm.col(m);
  return b;
}

struct Errors {
  double length_rms = 0, length_max = 0, moment_arm_rms = 0, moment_arm_max = 0;
  int worst_length = 0;
};

// RMS over the samples (moment arms: the largest of the coordinates' RMS, as OpenSim's tolerance
// applies per coordinate) and largest errors.
Errors errors_of(const VectorXd& residual, int n, int d) {
  Errors e;
  const VectorXd length = residual.head(n).cwiseAbs();
  e.length_rms = std::sqrt(length.squaredNorm() / n);
  e.length_max = length.maxCoeff(&e.worst_length);
  for (int m = 0; m < d; ++m) {
    const VectorXd arm = residual.segment((m + 1) * n, n);
    e.moment_arm_rms = std::max(e.moment_arm_rms, std::sqrt(arm.squaredNorm() / n));
    e.moment_arm_max = std::max(e.moment_arm_max, arm.cwiseAbs().maxCoeff());
  }
  return e;
}

// Least squares with the columns scaled to unit norm (the terms span many decades).
VectorXd solve_least_squares(const MatrixXd& A, const VectorXd& b) {
  VectorXd scale = A.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < scale.size(); ++j)
    if (scale[j] == 0.0) scale[j] = 1.0;
  const MatrixXd scaled = A * scale.cwiseInverse().asDiagonal();
  const VectorXd y = scaled.completeOrthogonalDecomposition().solve(b);
  return y.cwiseQuotient(scale);
}

// The arguments the path actually moves with: a joint between ground and the path's bodies that
// turns the whole path (a shoulder for a muscle of the forearm only) gives it no moment arm.
std::vector<std::string> moving_arguments(const OpenSimModel& model, const PathFitOptions& options,
                                          const GeometryPathEvaluator& path, const std::vector<std::string>& candidates) {
  if (candidates.empty()) return candidates;
  std::vector<VectorXd> probe, unused;
  unit_samples(static_cast<int>(candidates.size()), 500, probe, unused);
  const Samples s = PathSampler(model, options, path, candidates).sample(probe);
  std::vector<std::string> moving;
  for (std::size_t k = 0; k < candidates.size(); ++k)
    if (s.moment_arm.col(static_cast<int>(k)).cwiseAbs().maxCoeff() > 1e-9) moving.push_back(candidates[k]);
  return moving;
}

std::string coordinate_path(const OpenSimModel& model, const std::string& coordinate) {
  return "/jointset/" + model.coordinate(coordinate)->joint + "/" + coordinate;
}

}  // namespace

PathFit fit_polynomial_paths(const OpenSimModel& model, const OpenSimGeometryPaths& geometry, const PathFitOptions& options) {
  check_options(model, options);
  PathFit fit;
  std::vector<VectorXd> unit_fit, unit_check;
  for (const OpenSimGeometryPath& p : geometry.paths) {
    const GeometryPathEvaluator path(model, geometry, p.muscle);
    std::vector<std::string> arguments;
    for (const std::string& c : path.coordinates())
      if (options.ranges.count(c)) arguments.push_back(c);
    arguments = moving_arguments(model, options, path, arguments);
    if (arguments.empty()) continue;
    const int d = static_cast<int>(arguments.size());
    unit_samples(d, options.max_samples, unit_fit, unit_check);
    const PathSampler sampler(model, options, path, arguments);
    const Samples samples = sampler.sample(unit_fit);
    const VectorXd b = targets(samples);
    const int n = static_cast<int>(samples.length.size());

    PathFitReport report;
    VectorXd coefficients;
    for (int order = options.min_order; order <= options.max_order; ++order) {
      const MatrixXd A = design_matrix(samples.x, order);
      coefficients = solve_least_squares(A, b);
      const Errors e = errors_of(b - A * coefficients, n, d);
      report.order = order;
      report.tolerances_met = e.length_rms < options.length_tolerance_m && e.moment_arm_rms < options.moment_arm_tolerance_m;
      if (report.tolerances_met) break;
    }

    const Samples check = sampler.sample(unit_check);
    const VectorXd residual = targets(check) - design_matrix(check.x, report.order) * coefficients;
    const Errors e = errors_of(residual, static_cast<int>(check.length.size()), d);
    report.muscle = p.muscle;
    report.coordinates = arguments;
    report.samples = n;
    report.length_rms_m = e.length_rms;
    report.length_max_m = e.length_max;
    report.moment_arm_rms_m = e.moment_arm_rms;
    report.moment_arm_max_m = e.moment_arm_max;
    for (int k = 0; k < d; ++k) report.worst_length_posture.push_back(check.x(e.worst_length, k));

    OpenSimPolynomialPath out;
    out.force_path = "/forceset/" + p.muscle;
    out.muscle = p.muscle;
    for (const std::string& c : arguments) {
      out.coordinate_paths.push_back(coordinate_path(model, c));
      out.coordinates.push_back(c);
    }
    out.order = report.order;
    out.coefficients.assign(coefficients.data(), coefficients.data() + coefficients.size());
    fit.paths.push_back(std::move(out));
    fit.reports.push_back(std::move(report));
  }
  return fit;
}

}  // namespace flatsos::plugin
