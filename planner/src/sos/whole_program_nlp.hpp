#pragma once
// The reference formulation of the SOS program: the whole program as one Ipopt problem. Every
// constraint polynomial that the free coefficients theta can move gets its Markov-Lukacs
// certificate with single squares (numerics/lukacs_squares.hpp), p_jk(theta) = f^2 + s(1-s) g^2,
// so the unknowns are theta and every f and g, the equalities are the coefficient matching, and
// no Gram freedom is left (as many factor entries as coefficients). The cost is linear, the
// equalities quadratic: the Hessian of the Lagrangian is exact and constant in x. Started from a
// strictly feasible point that is not the optimum (the cheapest one with half the largest slack
// on a grid), with its certificates built from roots and multipliers from that grid LP's duals.
// Newton on this lifted problem alone wanders off (Ipopt's restoration fails on the arm), so a
// proximal term (rho/2)|x - x_last|^2 steadies it and vanishes: rounds with rho = 1, 0.1, ...,
// 1e-5, then rho = 0, each from the last round's point and multipliers; a round that fails is
// tried again from the same point with a smaller fall.

#include <vector>

#include <Eigen/Core>
#include <IpTNLP.hpp>

#include "flatsos/planner/sos_program.hpp"
#include "sos/sos_setup.hpp"

namespace flatsos::planner::detail {

// One certified constraint: scaled coefficients w (base + G theta + tolerance) of degree <= 2h
// (h from the highest power that is not zero for every theta: 2h = degree, or degree + 1),
// and where its f (h + 1 entries) and g (h entries) sit among Ipopt's variables.
struct SquaresBlock {
  std::size_t constraint = 0;
  int half = 0;
  double scale_N = 1.0;  // w = 1 / scale: the coefficients Ipopt matches are of order 1
  Eigen::VectorXd base;  // 2h + 1, scaled, with the tolerance added to the constant
  Eigen::MatrixXd G;     // (2h + 1) x theta, scaled
  int var_offset = 0, con_offset = 0;
  int rows() const { return 2 * half + 1; }
};

/// The Ipopt problem on these blocks (it keeps references to blocks and cost): variables theta
/// (cost.size()) then each block's f and g at its var_offset; the cost plus
/// (1/2) sum w_i (x_i - start_i)^2. For tests of its derivatives.
Ipopt::SmartPtr<Ipopt::TNLP> make_whole_program_nlp(const std::vector<SquaresBlock>& blocks, const Eigen::VectorXd& cost,
                                                    const Eigen::VectorXd& start, const Eigen::VectorXd& multipliers,
                                                    const Eigen::VectorXd& proximal_weights);

/// Solves the reserves' program; fills theta and the result's status, message, counts,
/// certification fields and solve_seconds; returns whether theta is a certified optimum.
bool solve_whole_program(const SosSetup& setup, const SosSettings& options, Eigen::VectorXd& theta,
                         SosProgramResult& result);

}  // namespace flatsos::planner::detail
