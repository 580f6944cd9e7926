#include "sos/whole_program_start.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "flatsos/planner/numerics/simplex_lp.hpp"
#include "numerics/lukacs_squares.hpp"

namespace flatsos::planner::detail {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {
// The start's grid: points per segment (uniform, ends included) at which the start LPs impose
// the constraints, and the slack they aim for (N): more only moves the start further inside.
constexpr int kStartPoints = 9;
constexpr double kStartSlackCap_N = 10.0;
}  // namespace


// The highest power whose coefficient is not zero for every theta. A block sized by the
// coefficient count instead would certify a degree-4 polynomial (padded to 7 coefficients on
// spline spans) with f^2 + s(1-s) g^2 of degree 6, whose top coefficients must cancel: f and g
// then share a root at infinity, and the equalities' Jacobian loses rank (Ipopt's restoration
// failed on the quartic on 2 spans).
Index structural_degree(const ConstraintPolynomial& c) {
  Index d = c.base.size() - 1;
  while (d > 0 && c.base[d] == 0.0 && (c.G.cols() == 0 || c.G.row(d).cwiseAbs().maxCoeff() == 0.0)) --d;
  return d;
}

bool moves_with_theta(const ConstraintPolynomial& c) { return c.G.size() > 0 && c.G.cwiseAbs().maxCoeff() > 0.0; }

// The start: on a grid of every segment, first the largest slack t (capped) with which every
// constraint can hold (>= t s^margin_order, so values the initial state fixes need none), then
// the cheapest theta with half of it. Returns false (with a reason) when the grid allows none.
bool strictly_feasible_start(const SosSetup& setup, const SosSettings& o, VectorXd& theta,
                             std::vector<StartDual>& duals, std::string& why) {
  const int n_theta = setup.free_coefficients;
  std::vector<std::pair<std::size_t, double>> points;  // (constraint, s)
  for (std::size_t c = 0; c < setup.constraints.size(); ++c)
    if (moves_with_theta(setup.constraints[c]))
      for (int i = 0; i < kStartPoints; ++i) points.emplace_back(c, i / (kStartPoints - 1.0));
  LinearProgram lp;
  const Index rows = static_cast<Index>(points.size());
  lp.G = MatrixXd::Zero(rows, n_theta + 1);
  lp.row_lower.resize(rows);
  lp.row_upper = VectorXd::Constant(rows, 1e19);
  for (Index r = 0; r < rows; ++r) {
    const ConstraintPolynomial& c = setup.constraints[points[static_cast<std::size_t>(r)].first];
    const double s = points[static_cast<std::size_t>(r)].second;
    const Eigen::RowVectorXd v = monomials(s, c.base.size());
    lp.G.row(r).head(n_theta) = v * c.G;
    lp.G(r, n_theta) = -std::pow(s, c.margin_order);
    lp.row_lower[r] = -v.dot(c.base);
  }
  lp.x_lower = VectorXd::Constant(n_theta + 1, -o.exchange.coefficient_bound_N);
  lp.x_upper = VectorXd::Constant(n_theta + 1, o.exchange.coefficient_bound_N);
  lp.x_lower[n_theta] = -1e19;
  lp.x_upper[n_theta] = kStartSlackCap_N;
  lp.cost = VectorXd::Zero(n_theta + 1);
  lp.cost[n_theta] = -1.0;
  const LinearProgramResult widest = solve_linear_program_simplex(lp);
  if (widest.status != SolveStatus::Solved || !(widest.x[n_theta] > 0.0)) {
    why = widest.status == SolveStatus::Solved
              ? "no flat outputs meet every constraint with a positive slack on the start grid"
              : "the start's LP failed (" + widest.solver_status + ")";
    return false;
  }
  lp.x_lower[n_theta] = lp.x_upper[n_theta] = 0.5 * widest.x[n_theta];
  lp.cost.head(n_theta) = setup.lp.cost;
  lp.cost[n_theta] = 0.0;
  const LinearProgramResult cheapest = solve_linear_program_simplex(lp);
  if (cheapest.status != SolveStatus::Solved) {
    why = "the start's LP failed (" + cheapest.solver_status + ")";
    return false;
  }
  theta = cheapest.x.head(n_theta);
  duals.clear();
  for (Index r = 0; r < rows; ++r)
    if (cheapest.row_multipliers[r] != 0.0)
      duals.push_back({points[static_cast<std::size_t>(r)].first, points[static_cast<std::size_t>(r)].second,
                       cheapest.row_multipliers[r]});
  return true;
}

std::string fixed_data_violation(const SosSetup& setup) {
  for (const ConstraintPolynomial& c : setup.constraints) {
    if (moves_with_theta(c)) continue;
    const IntervalMinimum low = minimum_on_interval(Polynomial(c.base), 0.0, 1.0);
    if (low.value >= -kConstraintTolerance_N) continue;
    std::ostringstream why;
    why << "infeasible: the boundary conditions fix the " << c.name << " on [" << c.t0_s << ", " << c.t1_s
        << "] s, and it falls " << -low.value << " N below its bound at t = " << c.t0_s + low.at * (c.t1_s - c.t0_s)
        << " s";
    return why.str();
  }
  return {};
}

WholeProgramStart blocks_from(const SosSetup& setup, const VectorXd& theta_start) {
  const int n_theta = setup.free_coefficients;
  WholeProgramStart out;
  out.block_of.assign(setup.constraints.size(), -1);
  out.x.assign(theta_start.data(), theta_start.data() + n_theta);
  for (std::size_t ci = 0; ci < setup.constraints.size(); ++ci) {
    const ConstraintPolynomial& c = setup.constraints[ci];
    if (!moves_with_theta(c)) continue;
    SquaresBlock b;
    b.constraint = ci;
    b.half = static_cast<int>(structural_degree(c) + 1) / 2;  // D <= 2h
    VectorXd at_start = c.base + c.G * theta_start;
    at_start[0] += kConstraintTolerance_N;  // certified: constraint >= -1e-9 N, as the exchange stops
    b.scale_N = std::max(1.0, at_start.cwiseAbs().maxCoeff());
    // An odd degree 2h - 1 uses the even family: one more row, whose coefficient is zero.
    const Index kept = std::min<Index>(b.rows(), c.base.size());
    b.base = VectorXd::Zero(b.rows());
    b.base.head(kept) = c.base.head(kept) / b.scale_N;
    b.base[0] += kConstraintTolerance_N / b.scale_N;
    b.G = MatrixXd::Zero(b.rows(), n_theta);
    b.G.topRows(kept) = c.G.topRows(kept) / b.scale_N;
    b.var_offset = static_cast<int>(out.x.size());
    b.con_offset = out.equalities;
    out.equalities += b.rows();
    const LukacsSquares squares = lukacs_squares(Polynomial(at_start / b.scale_N), b.half);
    out.x.insert(out.x.end(), squares.f.data(), squares.f.data() + squares.f.size());
    out.x.insert(out.x.end(), squares.g.data(), squares.g.data() + squares.g.size());
    out.block_of[ci] = static_cast<int>(out.blocks.size());
    out.blocks.push_back(std::move(b));
  }
  return out;
}

// Multipliers from the start LP's dual measure mu: the cost's gradient is sum mu grad p(s), so
// row k of block b gets -scale_b sum mu s^k, and the Hessian starts as the blocks' moment
// matrices, positive semidefinite, as at the optimum.
VectorXd start_multipliers(const WholeProgramStart& start, const std::vector<StartDual>& duals) {
  VectorXd lambda = VectorXd::Zero(start.equalities);
  for (const StartDual& d : duals) {
    const SquaresBlock& b = start.blocks[static_cast<std::size_t>(start.block_of[d.constraint])];  // duals are on moving ones
    for (int k = 0; k < b.rows(); ++k) lambda[b.con_offset + k] -= b.scale_N * d.weight * std::pow(d.s, k);
  }
  return lambda;
}

// Each block's factors certify its polynomial up to the residual (in N); a block counts as
// certified when that residual's l1 norm (a bound on its size over [0, 1]) is within the
// exchange's tolerance, so the constraint is proven >= -2e-9 N.
void record_certificates(const SosSetup& setup, const std::vector<SquaresBlock>& blocks, const VectorXd& solution,
                         const VectorXd& theta, SosProgramResult& result) {
  result.near_active_pieces = static_cast<int>(blocks.size());
  result.certified_pieces = 0;
  double worst_residual_N = 0.0;
  for (const SquaresBlock& b : blocks) {
    const LukacsSquares sq{solution.segment(b.var_offset, b.half + 1), solution.segment(b.var_offset + b.half + 1, b.half)};
    const VectorXd residual = b.scale_N * (b.base + b.G * theta - lukacs_squares_polynomial(sq));
    const double l1 = residual.cwiseAbs().sum();
    worst_residual_N = std::max(worst_residual_N, l1);
    if (l1 <= kConstraintTolerance_N) ++result.certified_pieces;
  }
  result.certified = result.certified_pieces == result.near_active_pieces;
  result.min_constraint_value_N = std::numeric_limits<double>::infinity();
  for (const ConstraintPolynomial& c : setup.constraints)
    result.min_constraint_value_N = std::min(result.min_constraint_value_N, minimum_on_interval(c.at(theta), 0.0, 1.0).value);
  result.max_certificate_residual_N = worst_residual_N;
}

}  // namespace flatsos::planner::detail
