#pragma once
// A Lukacs certificate assembled from a polynomial's roots, without an optimization: the
// constructive proof of Lukacs' theorem (Polya & Szego, Problems and Theorems in Analysis II,
// VI.47; Powers & Reznick, "Polynomials that are positive on an interval", Trans. AMS 352, 2000).
#include <optional>

#include <Eigen/Core>

#include "flatsos/planner/numerics/sos_certificate.hpp"

namespace flatsos::planner::detail {

/// p (monomial coefficients, the last nonzero, degree >= 1) written as its leading coefficient
/// times its root factors, each factor nonnegative on [0, 1] in Lukacs form:
///   s - r = (1 - r) s + (-r)(1 - s)             (a real root r <= 0)
///   r - s = (r - 1) s + r (1 - s)               (a real root r >= 1)
///   (s - m)^2                                   (a pair of real roots in (0, 1), m their mean)
///   (s - a)^2 + b^2 = (s - a)^2 + b^2 (s^2 + (1 - s)^2 + 2 s (1 - s))   (roots a +- i b)
/// multiplied into a certificate by the exact algebra of lukacs_algebra.hpp. An odd root left in
/// (0, 1) is moved to the nearer end. The result's residual is not checked here (the caller
/// decides, as for any certificate); none when the signs do not come out nonnegative (p < 0
/// somewhere on [0, 1], or a root count that leaves the leading factor negative).
std::optional<LukacsCertificate> certificate_from_roots(const Eigen::VectorXd& p, GramBasis basis);

}  // namespace flatsos::planner::detail
