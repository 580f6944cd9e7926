#include "flatsos/planner/separable_power_program.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>

namespace flatsos::planner {

namespace {

// The variables minimizing the Lagrangian for s = B^T lambda, their slopes dx/ds (0 at a bound)
// and the dual function's value.
struct DualPoint {
  Eigen::VectorXd x, slope;
  double value = 0.0;
};

void minimize_lagrangian(const SeparablePowerProgram& P, const Eigen::VectorXd& lambda, DualPoint& out) {
  const double p = P.exponent, q = 1.0 / (p - 1.0);
  const Eigen::VectorXd s = P.B.transpose() * lambda;
  out.x.resize(s.size());
  out.slope.resize(s.size());
  double effort = 0.0;
  for (Eigen::Index j = 0; j < s.size(); ++j) {
    const double scaled = s[j] / (p * P.weights[j]), magnitude = std::abs(scaled);
    const double u = std::copysign(std::pow(magnitude, q), scaled);
    const double x = std::clamp(u, P.lower[j], P.upper[j]);
    out.x[j] = x;
    // The closed interval counts as inside: at x = 0 on a lower bound of 0 the generalized
    // derivative keeps the variable in the Newton system (a semismooth Newton step).
    const bool inside = u >= P.lower[j] && u <= P.upper[j];
    out.slope[j] = inside ? q * std::pow(std::max(magnitude, 1e-12), q - 1.0) / (p * P.weights[j]) : 0.0;
    effort += P.weights[j] * std::pow(std::abs(x), p);
  }
  out.value = effort - lambda.dot(P.B * out.x - P.b);
}

// A Farkas certificate that no x in the box meets B x = b: y^T b beyond the largest y^T B x over
// the box (sum_j max(s_j lower_j, s_j upper_j), s = B^T y; infinite where a bound is).
bool certifies_infeasible(const SeparablePowerProgram& P, const Eigen::VectorXd& y) {
  if (!y.allFinite() || y.isZero()) return false;
  const Eigen::VectorXd s = P.B.transpose() * y;
  double reach = 0.0;
  for (Eigen::Index j = 0; j < s.size(); ++j) {
    if (s[j] == 0.0) continue;
    const double bound = s[j] > 0.0 ? P.upper[j] : P.lower[j];
    if (!std::isfinite(bound)) return false;
    reach += s[j] * bound;
  }
  return y.dot(P.b) > reach + 1e-9 * (std::abs(reach) + y.cwiseAbs().dot(P.b.cwiseAbs()));
}

void validate(const SeparablePowerProgram& P) {
  const Eigen::Index n = P.B.cols();
  if (P.B.rows() < 1 || n < 1) throw std::invalid_argument("separable power program: B needs at least one row and one column");
  if (P.b.size() != P.B.rows() || P.weights.size() != n || P.lower.size() != n || P.upper.size() != n)
    throw std::invalid_argument("separable power program: B, b, weights and bounds have inconsistent sizes");
  if (!(P.exponent > 1.0) || !std::isfinite(P.exponent))
    throw std::invalid_argument("separable power program: the exponent must be a finite number > 1");
  if (!P.B.allFinite() || !P.b.allFinite()) throw std::invalid_argument("separable power program: B and b must be finite");
  for (Eigen::Index j = 0; j < n; ++j) {
    if (!(P.weights[j] > 0.0) || !std::isfinite(P.weights[j]))
      throw std::invalid_argument("separable power program: weight " + std::to_string(j) + " must be finite and > 0");
    if (!(P.lower[j] < P.upper[j]))
      throw std::invalid_argument("separable power program: bound " + std::to_string(j) + ": lower must be below upper");
  }
}

}  // namespace

SeparablePowerSolution solve_separable_power_program(const SeparablePowerProgram& P, double tolerance,
                                                     int max_iterations) {
  validate(P);
  SeparablePowerSolution out;
  const Eigen::Index rows = P.B.rows();
  const double scale = std::max(1.0, P.b.cwiseAbs().maxCoeff());
  // Start from the multipliers of the program without bounds at p = 2.
  const Eigen::MatrixXd BWBt = P.B * P.weights.cwiseInverse().asDiagonal() * P.B.transpose();
  Eigen::VectorXd lambda = 2.0 * BWBt.ldlt().solve(P.b);
  if (!lambda.allFinite()) lambda.setZero(rows);
  DualPoint point, trial;
  minimize_lagrangian(P, lambda, point);
  Eigen::VectorXd gradient = P.b - P.B * point.x;
  for (out.iterations = 0; out.iterations < max_iterations; ++out.iterations) {
    if (gradient.cwiseAbs().maxCoeff() <= tolerance * scale) break;
    // Newton on the concave dual: (B D B^T) step = b - B x, regularized where D vanishes.
    Eigen::MatrixXd H = P.B * point.slope.asDiagonal() * P.B.transpose();
    const double trace = H.trace();
    if (!(trace > 0.0)) break;  // every variable at a bound, and a row still missed
    H.diagonal().array() += 1e-12 * trace;
    const Eigen::VectorXd step = H.llt().solve(gradient);
    // Backtracking (Armijo) on the dual function.
    double t = 1.0;
    const double slope = gradient.dot(step);
    bool accepted = false;
    for (int halving = 0; halving < 60 && !accepted; ++halving, t *= 0.5) {
      minimize_lagrangian(P, lambda + t * step, trial);
      accepted = trial.value >= point.value + 1e-4 * t * slope || t * step.cwiseAbs().maxCoeff() <= 1e-15 * (1.0 + lambda.cwiseAbs().maxCoeff());
      if (accepted) lambda += t * step;
    }
    if (!accepted) break;
    std::swap(point, trial);
    gradient = P.b - P.B * point.x;
    if (!lambda.allFinite() || lambda.cwiseAbs().maxCoeff() > 1e15 * scale) break;  // the dual grows without bound
  }
  out.x = point.x;
  out.multipliers = lambda;
  out.residual = gradient.cwiseAbs().maxCoeff();
  out.objective = (P.weights.array() * out.x.array().abs().pow(P.exponent)).sum();
  out.solved = out.residual <= tolerance * scale && out.x.allFinite();
  if (!out.solved) {
    // Infeasible only with a certificate: the dual's direction of growth, or its gradient.
    out.infeasible = certifies_infeasible(P, lambda) || certifies_infeasible(P, gradient);
    Eigen::Index row = 0;
    gradient.cwiseAbs().maxCoeff(&row);
    out.worst_row = static_cast<int>(row);
    out.message = (out.infeasible ? "B x = b has no solution within the bounds: row "
                                  : "the dual Newton method stopped before it converged: row ") +
                  std::to_string(row) + " is missed by " + std::to_string(gradient[row]) + " after " +
                  std::to_string(out.iterations) + " iterations";
  }
  return out;
}

}  // namespace flatsos::planner
