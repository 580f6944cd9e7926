#pragma once
// Markov-Lukacs with single squares: a polynomial p of degree <= 2h that is >= 0 on [0, 1] is
//   p(s) = f(s)^2 + s (1 - s) g(s)^2,   deg f <= h, deg g <= h - 1,
// with as many unknowns (2h + 1) as coefficients, so no Gram freedom is left (the Gram matrices
// are f f^T and g g^T). Odd degrees use the next even one (its top coefficient 0). Built here
// from p's roots: each root pair (complex, or two real ones outside [0, 1]) or single real root
// outside gives a factor q >= 0 on [0, 1] of degree <= 2 written as F^2 + s(1-s) G^2 in closed
// form, and such forms multiply like complex numbers:
//   (f^2 + D g^2)(F^2 + D G^2) = (f F - D g G)^2 + D (f G + g F)^2,   D = s (1 - s).

#include <Eigen/Core>

#include "flatsos/planner/numerics/polynomial.hpp"

namespace flatsos::planner::detail {

struct LukacsSquares {
  Eigen::VectorXd f;  ///< monomial coefficients, h + 1 of them
  Eigen::VectorXd g;  ///< h of them
};

/// f and g (h = half_degree) with f^2 + s(1-s) g^2 close to p: exact up to the roots' rounding
/// when p > 0 on [0, 1]; for p with zeros in [0, 1] (numerically split into close real roots)
/// or negative somewhere, the nearest such form the roots suggest (a start for Newton, not a
/// certificate). Throws std::invalid_argument when p's degree exceeds 2 h.
LukacsSquares lukacs_squares(const Polynomial& p, int half_degree);

/// Monomial coefficients (2h + 1) of f^2 + s(1-s) g^2.
Eigen::VectorXd lukacs_squares_polynomial(const LukacsSquares& squares);

}  // namespace flatsos::planner::detail
