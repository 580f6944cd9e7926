#pragma once
// Excitations for one control period: the inverse map's samples on a uniform grid over the period
// fitted, per muscle, by one least-squares polynomial of scaled time (no kinks inside the period
// for the integrator to resolve). The fit's matrix depends only on the sample count, so it is
// factored once, before the control loop (acados' split of preparation and feedback).

#include <memory>

#include <Eigen/Core>
#include <Eigen/QR>

#include "flatsos/planner/numerics/polynomial.hpp"
#include "flatsos/plugin/force/excitation_signal.hpp"

namespace flatsos::planner {

class ExcitationFitter {
 public:
  /// Degree of the fit: n(t) is smooth over a period (a cubic path, constant Y), and degree 6
  /// reproduces it to ~1e-6 (measured on the arm).
  static constexpr int kMaxDegree = 6;

  /// Throws std::invalid_argument for fewer than 2 samples or a period that is not > 0 s.
  ExcitationFitter(int samples_per_period, double period_s);

  int samples() const { return samples_; }
  double period_s() const { return period_s_; }
  /// Time between samples: sample i is at t0 + i spacing_s().
  double spacing_s() const { return period_s_ / (samples_ - 1); }
  /// The polynomial of s = (t - t0) / period through one muscle's samples (least squares).
  Polynomial fit(const Eigen::VectorXd& samples) const;
  /// The signal n(t) = p((t - t0) / period), held at the period's ends.
  std::shared_ptr<const plugin::ExcitationSignal> signal(Polynomial fitted, double t0_s) const;

 private:
  int samples_;
  double period_s_;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr_;
};

}  // namespace flatsos::planner
