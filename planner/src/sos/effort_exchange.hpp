#pragma once
// The open-loop plan's nonlinear effort (effort.hpp: squared or cubed excitations, activations
// or stresses): from the optimum of the map's linear effort, which meets the reserves and the
// bounds, a sequential QP over the flat outputs' coefficients theta minimizes the effort's
// Gauss-Legendre quadrature on every segment of the program (the torque pieces refined by the
// spline's spans), with the reserve rows of the exchange as they are and the bound rows at their
// points linearized. After each QP sequence the exact minima of the reserve polynomials and the
// bounds on the check grid are searched: violations join as points, and the sequence resumes,
// until nothing is violated (the exchange of sos_exchange.hpp and sos_bounds.hpp, with a convex
// model of the effort in place of the linear cost).

#include <vector>

#include "flatsos/planner/effort.hpp"
#include "sos/sos_settings.hpp"
#include "sos/sos_setup.hpp"

namespace flatsos::planner::detail {

/// Gauss-Legendre points per segment of the effort's quadrature.
constexpr int kEffortGaussPoints = 4;

/// The effort's quadrature: kEffortGaussPoints Gauss-Legendre points on every segment between
/// consecutive `ends` (any order; ends closer than 1e-12 s count as one).
struct EffortQuadrature {
  std::vector<double> times_s, weights_s;
};
EffortQuadrature effort_quadrature(std::vector<double> ends_s);

/// Moves theta to the minimum of `effort` and fills result's effort fields. False with result's
/// status and message when it fails; theta is then where it stopped.
bool minimize_effort_by_exchange(SosSetup& setup, const MusclesAlongPath& muscles, const SosSettings& options,
                                 const Effort& effort, Eigen::VectorXd& theta, SosProgramResult& result);

}  // namespace flatsos::planner::detail
