#pragma once
// The SOS program's solvers: the exchange (cutting-plane) method on the set-up program, and the
// Lukacs certification of the pieces that come near zero.

#include <Eigen/Core>

#include "flatsos/planner/numerics/simplex_lp.hpp"

#include "sos/sos_setup.hpp"

namespace flatsos::planner::detail {

/// Solves the semi-infinite LP by exchange: LPs on finitely many points (Clp's dual simplex, or
/// Ipopt when the options say so), the exact minimum of every constraint polynomial
/// adding violated points, until none is violated. Fills theta and the result's status, message,
/// counts and solve_seconds; returns whether a feasible optimum was found. `basis`, when given,
/// receives the last LP's basis by row identity (the coefficients', every constraint point's):
/// the bounds' sequential LP starts from it, and so does a second call (when it fits). `tolerance_N`: how far below 0 a constraint's
/// minimum may stay (kLooseConstraintTolerance_N: a start for the bounds' exchange, which
/// finishes the reserves'). A second call goes on from the points the first one left.
bool solve_by_exchange(SosSetup& setup, const SosSettings& options, Eigen::VectorXd& theta,
                       SosProgramResult& result, SequentialLpBasis* basis = nullptr, double tolerance_N = kConstraintTolerance_N);

/// Lukacs certificates (one Ipopt problem) for the pieces whose constraint minimum is below
/// options.near_active_N; fills the certification fields and certify_seconds.
void certify_near_active_pieces(const SosSetup& setup, const Eigen::VectorXd& theta, const SosSettings& options,
                                SosProgramResult& result);

}  // namespace flatsos::planner::detail
