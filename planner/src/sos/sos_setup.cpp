#include "sos/sos_setup.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <Eigen/Dense>

#include "numerics/lukacs_basis.hpp"

namespace flatsos::planner::detail {

Eigen::RowVectorXd monomials(double s, Eigen::Index size) {
  Eigen::RowVectorXd v(size);
  double p = 1.0;
  for (Eigen::Index j = 0; j < size; ++j, p *= s) v[j] = p;
  return v;
}

std::string fixed_violation(const SosSetup& setup, double margin_N) {
  for (const auto& c : setup.constraints) {
    std::vector<double> where = c.points;
    if (c.t0_s == 0.0) where.push_back(0.0);  // t = 0, even where it is no LP point
    for (double s : where) {
      const Eigen::RowVectorXd v = monomials(s, c.base.size());
      const Eigen::RowVectorXd row = v * c.G;
      const double value = v.dot(c.base);
      // Eigen's maxCoeff on an empty vector is undefined: with no free coefficient (the
      // equalities fix Y completely) every row is fixed.
      const double row_size = row.size() ? row.cwiseAbs().maxCoeff() : 0.0;
      const double g_size = c.G.size() ? c.G.cwiseAbs().maxCoeff() : 0.0;
      if (row_size <= 1e-12 * (1.0 + g_size) && value < -margin_N) {
        const double t = c.t0_s + s * (c.t1_s - c.t0_s);
        std::ostringstream why;
        why << "infeasible: at t = " << t << " s the boundary conditions fix Y, and ";
        if (c.muscle >= 0)
          why << "the guaranteed " << c.name << " is " << -value << " N below its reserve of " << c.reserve_N
              << " N (the torque model's remainder bound costs " << c.remainder_cost_N(s)
              << " N there: use more pieces K or a higher degree r)";
        else
          why << c.name << " is violated by " << -value << " N";
        return why.str();
      }
    }
  }
  return "";
}

int build_exchange_rows(SosSetup& setup, double margin_N) {
  std::size_t rows = 0;
  for (const auto& c : setup.constraints) rows += c.points.size();
  LinearProgram& lp = setup.lp;
  lp.G.resize(static_cast<Eigen::Index>(rows), setup.free_coefficients);
  lp.row_lower.resize(static_cast<Eigen::Index>(rows));
  lp.row_upper = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(rows), 1e19);
  Eigen::Index row = 0;
  for (const auto& c : setup.constraints)
    for (double s : c.points) {
      const Eigen::RowVectorXd v = monomials(s, c.base.size());
      lp.G.row(row) = v * c.G;
      double extra = 0.0;
      for (const auto& [at, margin] : c.extra_margin)
        if (at == s) extra += margin;
      lp.row_lower[row] = margin_N * std::pow(s, c.margin_order) + extra - v.dot(c.base);
      ++row;
    }
  return static_cast<int>(rows);
}

bool add_violated_points(SosSetup& setup, const Eigen::VectorXd& theta, double margin_N, double& min_value_N,
                         double tolerance_N, double lift_below_N) {
  bool added = false;
  min_value_N = 1e300;
  // A polynomial on [0, 1] is at least its least Bernstein coefficient. Exact minima (the
  // derivative's roots, by eigenvalues) are found smallest bound first, and no longer once a
  // bound shows no violation and no new least value: the same points and least value for a
  // fraction of the cost where most segments are far from their reserve.
  struct Segment {
    double lower;
    std::size_t index;
    Polynomial p;
  };
  std::vector<Segment> segments;
  segments.reserve(setup.constraints.size());
  for (std::size_t k = 0; k < setup.constraints.size(); ++k) {
    Polynomial p = setup.constraints[k].at(theta);
    // Less the conversion's rounding (sums of the coefficients' size), so that the bound stays one.
    const double lower = from_monomial(GramBasis::Bernstein, p.coefficients()).minCoeff() -
                         1e-13 * (1.0 + p.coefficients().cwiseAbs().sum());
    segments.push_back({std::isnan(lower) ? -std::numeric_limits<double>::infinity() : lower, k, std::move(p)});
  }
  std::sort(segments.begin(), segments.end(), [](const Segment& a, const Segment& b) { return a.lower < b.lower; });
  for (const Segment& segment : segments) {
    if (segment.lower >= min_value_N && segment.lower >= -tolerance_N) break;
    auto& c = setup.constraints[segment.index];
    const IntervalMinimum mn = minimum_on_interval(segment.p, 0.0, 1.0);
    min_value_N = std::min(min_value_N, mn.value);
    if (mn.value < -tolerance_N) {
      const auto known = std::find_if(c.points.begin(), c.points.end(), [&](double s) { return std::abs(s - mn.at) < 1e-9; });
      if (known == c.points.end()) {
        c.points.push_back(mn.at);
        c.sticky.push_back(true);
        if (-mn.value <= lift_below_N) c.extra_margin.emplace_back(mn.at, -mn.value);
      } else {
        // Violated at a point the LP already imposes: it met the row only to its own precision
        // (near t = 0 the margin s^order vanishes, and the bounds' sequential LP holds rows to
        // half the margin). The full margin and twice the violation there, and again if need be.
        c.extra_margin.emplace_back(*known, margin_N - 2.0 * mn.value);
      }
      added = true;
    }
  }
  return added;
}

// Y_l's B-spline coefficients = particular + nullspace theta_l under the boundary equalities.
// The equalities touch only the first and last few coefficients (local support), so the free
// coefficients theta_l are the other B-spline coefficients themselves and the solved-for ones
// depend only on their neighbours: the constraint rows stay sparse and local, and theta is as
// well scaled as the coefficients (newtons). The solved-for columns are chosen by full pivoting.
OutputParameterization eliminate_equalities(const BSplineBasis& basis, const FlatOutputBoundary& bc, int l) {
  const int n_eq = static_cast<int>(bc.initial.cols() + bc.terminal.cols());
  const int size = basis.size();
  Eigen::MatrixXd Aeq(n_eq, size);
  Eigen::VectorXd beq(n_eq);
  int row = 0;
  for (int k = 0; k < bc.initial.cols(); ++k, ++row) {
    Aeq.row(row) = basis.derivativeRow(0.0, k);
    beq[row] = bc.initial(l, k);
  }
  for (int k = 0; k < bc.terminal.cols(); ++k, ++row) {
    Aeq.row(row) = basis.derivativeRow(basis.duration(), bc.terminal_first_order + k);
    beq[row] = bc.terminal(l, k);
  }
  // Each row in units of its largest entry: a derivative of order k scales as 1/h^k, and short
  // spans next to long ones (graded knots) would otherwise fail the rank test on scale alone.
  for (int r = 0; r < n_eq; ++r) {
    const double scale = Aeq.row(r).cwiseAbs().maxCoeff();
    if (scale > 0.0) Aeq.row(r) /= scale, beq[r] /= scale;
  }
  OutputParameterization out;
  out.particular = Eigen::VectorXd::Zero(size);
  if (n_eq == 0) {
    out.nullspace = Eigen::MatrixXd::Identity(size, size);
    return out;
  }
  Eigen::FullPivLU<Eigen::MatrixXd> lu(Aeq);
  lu.setThreshold(1e-10);
  if (lu.rank() < n_eq)
    throw std::invalid_argument("SOS program: the boundary equalities on Y are dependent for this basis");
  std::vector<bool> solved_for(static_cast<std::size_t>(size), false);
  Eigen::MatrixXd A_dep(n_eq, n_eq), A_free(n_eq, size - n_eq);
  std::vector<int> dependent, free;
  for (int i = 0; i < n_eq; ++i) solved_for[static_cast<std::size_t>(lu.permutationQ().indices()[i])] = true;
  for (int j = 0; j < size; ++j) (solved_for[static_cast<std::size_t>(j)] ? dependent : free).push_back(j);
  for (int i = 0; i < n_eq; ++i) A_dep.col(i) = Aeq.col(dependent[static_cast<std::size_t>(i)]);
  for (int i = 0; i < size - n_eq; ++i) A_free.col(i) = Aeq.col(free[static_cast<std::size_t>(i)]);
  const Eigen::PartialPivLU<Eigen::MatrixXd> dep(A_dep);
  const Eigen::VectorXd c_dep = dep.solve(beq);
  out.nullspace = Eigen::MatrixXd::Zero(size, size - n_eq);
  for (int i = 0; i < n_eq; ++i) out.particular[dependent[static_cast<std::size_t>(i)]] = c_dep[i];
  // With no free coefficient (the equalities fix Y) there is no coupling to solve for: Eigen's
  // triangular solve on a matrix without columns binds a reference to null data (UBSan).
  if (size > n_eq) {
    const Eigen::MatrixXd coupling = -dep.solve(A_free);
    for (int i = 0; i < n_eq; ++i) out.nullspace.row(dependent[static_cast<std::size_t>(i)]) = coupling.row(i);
  }
  for (int i = 0; i < size - n_eq; ++i) out.nullspace(free[static_cast<std::size_t>(i)], i) = 1.0;
  return out;
}

SplineTrajectory flat_outputs_of(const SosSetup& setup, const Eigen::VectorXd& theta) {
  Eigen::MatrixXd coefficients(static_cast<Eigen::Index>(setup.outputs.size()), setup.basis.size());
  for (std::size_t l = 0; l < setup.outputs.size(); ++l) {
    const auto& out = setup.outputs[l];
    Eigen::VectorXd c = out.particular;
    if (out.nullspace.cols()) c += out.nullspace * theta.segment(out.offset, out.nullspace.cols());
    coefficients.row(static_cast<Eigen::Index>(l)) = c.transpose();
  }
  return SplineTrajectory(setup.basis, std::move(coefficients));
}

Eigen::VectorXd theta_of(const SosSetup& setup, const SplineTrajectory& Y) {
  if (Y.basis().size() != setup.basis.size() || Y.signals() != static_cast<int>(setup.outputs.size()))
    throw std::logic_error("theta_of: the flat outputs are not in the program's basis");
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(setup.free_coefficients);
  for (std::size_t l = 0; l < setup.outputs.size(); ++l) {
    const auto& out = setup.outputs[l];
    if (!out.nullspace.cols()) continue;
    const Eigen::VectorXd rest = Y.coefficients().row(static_cast<Eigen::Index>(l)).transpose() - out.particular;
    theta.segment(out.offset, out.nullspace.cols()) = out.nullspace.colPivHouseholderQr().solve(rest);
  }
  return theta;
}

}  // namespace flatsos::planner::detail
