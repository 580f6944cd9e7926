#include "flatsos/plugin/io/natural_quintic_spline.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>

namespace flatsos::plugin {
namespace {

// An affine function of one interval's end derivatives, scaled by a reference spacing H:
// (u0, w0, u1, w1) = (H f'(left), H^2 f''(left), H f'(right), H^2 f''(right)), plus a constant.
using Affine = Eigen::Matrix<double, 5, 1>;

Affine unit(int i) { return Affine::Unit(i); }

// The interval's quintic in s = (x - x_left)/h as affine forms c0..c5 (r = h/H, rise = y1 - y0,
// with y0 taken out of c0): the Hermite quintic matching value, slope and curvature at both ends.
std::array<Affine, 6> hermite_coefficients(double r, double rise) {
  std::array<Affine, 6> c;
  c[0] = Affine::Zero();
  c[1] = r * unit(0);
  c[2] = 0.5 * r * r * unit(1);
  const Affine value_gap = rise * unit(4) - c[1] - c[2];
  const Affine slope_gap = r * unit(2) - c[1] - 2.0 * c[2];
  const Affine curvature_gap = r * r * unit(3) - 2.0 * c[2];
  c[3] = 10.0 * value_gap - 4.0 * slope_gap + 0.5 * curvature_gap;
  c[4] = -15.0 * value_gap + 7.0 * slope_gap - curvature_gap;
  c[5] = 6.0 * value_gap - 3.0 * slope_gap + 0.5 * curvature_gap;
  return c;
}

// H^3 f''' and H^4 f'''' at the interval's left and right ends.
struct EndDerivatives {
  Affine third_left, fourth_left, third_right, fourth_right;
};

EndDerivatives end_derivatives(double r, double rise) {
  const auto c = hermite_coefficients(r, rise);
  const double r3 = r * r * r, r4 = r3 * r;
  return {6.0 * c[3] / r3, 24.0 * c[4] / r4, (6.0 * c[3] + 24.0 * c[4] + 60.0 * c[5]) / r3,
          (24.0 * c[4] + 120.0 * c[5]) / r4};
}

void check_knots(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size())
    throw std::invalid_argument("NaturalQuinticSpline: " + std::to_string(x.size()) + " knots but " +
                                std::to_string(y.size()) + " values");
  if (x.size() < 6)
    throw std::invalid_argument("NaturalQuinticSpline: needs at least 6 knots, got " + std::to_string(x.size()));
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i]))
      throw std::invalid_argument("NaturalQuinticSpline: knot " + std::to_string(i) + " is not finite");
    if (i > 0 && !(x[i] > x[i - 1]))
      throw std::invalid_argument("NaturalQuinticSpline: knots must increase strictly; x[" + std::to_string(i) +
                                  "] = " + std::to_string(x[i]) + " follows " + std::to_string(x[i - 1]));
  }
}

// Rows 2i and 2i+1 hold the third- and fourth-derivative conditions at knot i: zero at the two
// ends, continuity inside. Unknowns 2i and 2i+1 are knot i's u and w.
Eigen::VectorXd solve_knot_derivatives(const std::vector<double>& x, const std::vector<double>& y, double H) {
  const int n = static_cast<int>(x.size());
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(2 * n);
  auto add = [&](int row, int interval, const Affine& form, double sign) {
    for (int k = 0; k < 4; ++k) entries.emplace_back(row, 2 * interval + k, sign * form(k));
    rhs(row) -= sign * form(4);
  };
  for (int j = 0; j + 1 < n; ++j) {
    const EndDerivatives d = end_derivatives((x[j + 1] - x[j]) / H, y[j + 1] - y[j]);
    add(2 * j, j, d.third_left, -1.0);
    add(2 * j + 1, j, d.fourth_left, -1.0);
    add(2 * j + 2, j, d.third_right, 1.0);
    add(2 * j + 3, j, d.fourth_right, 1.0);
  }
  Eigen::SparseMatrix<double> system(2 * n, 2 * n);
  system.setFromTriplets(entries.begin(), entries.end());
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu;
  lu.compute(system);
  if (lu.info() != Eigen::Success)
    throw std::invalid_argument("NaturalQuinticSpline: the knots give a singular system");
  return lu.solve(rhs);
}

}  // namespace

NaturalQuinticSpline::NaturalQuinticSpline(std::vector<double> x, const std::vector<double>& y) : x_(std::move(x)) {
  check_knots(x_, y);
  const std::size_t n = x_.size();
  const double H = (x_.back() - x_.front()) / static_cast<double>(n - 1);
  const Eigen::VectorXd z = solve_knot_derivatives(x_, y, H);
  coefficients_.resize(n - 1);
  for (std::size_t j = 0; j + 1 < n; ++j) {
    const auto forms = hermite_coefficients((x_[j + 1] - x_[j]) / H, y[j + 1] - y[j]);
    Affine unknowns;
    unknowns << z(2 * j), z(2 * j + 1), z(2 * j + 2), z(2 * j + 3), 1.0;
    coefficients_[j].resize(6);
    for (int k = 0; k < 6; ++k) coefficients_[j][k] = forms[k].dot(unknowns);
    coefficients_[j][0] = y[j];
  }
}

double NaturalQuinticSpline::derivative(double x, int order) const {
  if (!(x >= x_.front() && x <= x_.back()))
    throw std::invalid_argument("NaturalQuinticSpline: x = " + std::to_string(x) + " lies outside the knots [" +
                                std::to_string(x_.front()) + ", " + std::to_string(x_.back()) + "]");
  return continuedDerivative(x, order);
}

double NaturalQuinticSpline::continuedDerivative(double x, int order) const {
  if (order < 0 || order > 5)
    throw std::invalid_argument("NaturalQuinticSpline: derivative order must be 0..5, got " + std::to_string(order));
  if (!std::isfinite(x)) throw std::invalid_argument("NaturalQuinticSpline: x is not finite");
  // The interval holding x; before the first knot the first, after the last knot the last.
  const auto after = std::upper_bound(x_.begin(), x_.end(), x);
  const std::size_t index = after == x_.begin() ? 0 : static_cast<std::size_t>(after - x_.begin()) - 1;
  const std::size_t j = std::min<std::size_t>(index, x_.size() - 2);
  const double h = x_[j + 1] - x_[j];
  const double s = (x - x_[j]) / h;
  const std::vector<double>& c = coefficients_[j];
  double sum = 0.0;  // Horner on the order-th derivative in s
  for (int p = 5; p >= order; --p) {
    double falling = 1.0;  // p! / (p - order)!
    for (int k = 0; k < order; ++k) falling *= static_cast<double>(p - k);
    sum = sum * s + falling * c[static_cast<std::size_t>(p)];
  }
  return sum / std::pow(h, order);
}

}  // namespace flatsos::plugin
