#pragma once
// Excitations for one control period: the inverse map's samples on a uniform grid over the period
// fitted, per muscle, by one least-squares polynomial of scaled time (no kinks inside the period
// for the integrator to resolve). The fit's matrix depends only on the sample count, so its
// least-squares solution operator is computed once, before the control loop (acados' split of
// preparation and feedback); per period a fit is one small matrix-vector product into a
// plugin::ExcitationPolynomial, which the muscle keeps by value: nothing is allocated.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <Eigen/Core>

#include "flatsos/plugin/force/excitation_signal.hpp"

namespace flatsos::planner {

class ExcitationFitter {
 public:
  /// Degree of the fit: n(t) is smooth over a period (a cubic path, constant Y), and degree 6
  /// reproduces it to ~1e-6 (measured on the arm).
  static constexpr int kMaxDegree = 6;
  static_assert(kMaxDegree < plugin::ExcitationPolynomial::kMaxCoefficients, "the piece must hold the fit");

  /// Throws std::invalid_argument for fewer than 2 samples or a period that is not > 0 s.
  ExcitationFitter(int samples_per_period, double period_s);

  int samples() const { return samples_; }
  double period_s() const { return period_s_; }
  /// Time between samples: sample i is at t0 + i spacing_s().
  double spacing_s() const { return period_s_ / (samples_ - 1); }
  /// The piece n(t) = p((t - t0) / period), held at the period's ends, whose polynomial p fits
  /// one muscle's samples (least squares). Throws std::invalid_argument for a wrong sample count.
  plugin::ExcitationPolynomial fit(const Eigen::Ref<const Eigen::VectorXd>& samples, double t0_s) const;

 private:
  int samples_;
  double period_s_;
  Eigen::MatrixXd solution_operator_;  ///< (degree + 1) x samples: V^+ of the Vandermonde matrix
};

}  // namespace flatsos::planner
