#include "flatsos/planner/excitation_fitter.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace flatsos::planner {

namespace {
class PolynomialSignal final : public plugin::ExcitationSignal {
 public:
  PolynomialSignal(Polynomial p, double t0, double duration) : p_(std::move(p)), t0_(t0), duration_(duration) {}
  double value(double t) const override { return p_(std::clamp((t - t0_) / duration_, 0.0, 1.0)); }

 private:
  Polynomial p_;
  double t0_, duration_;
};

Eigen::MatrixXd vandermonde(int samples, int degree) {
  Eigen::MatrixXd V(samples, degree + 1);
  for (int i = 0; i < samples; ++i)
    for (int k = 0; k <= degree; ++k) V(i, k) = std::pow(static_cast<double>(i) / (samples - 1), k);
  return V;
}
}  // namespace

ExcitationFitter::ExcitationFitter(int samples, double period_s) : samples_(samples), period_s_(period_s) {
  if (samples < 2) throw std::invalid_argument("RH controller: need at least 2 excitation samples per period");
  if (!(period_s > 0.0) || !std::isfinite(period_s)) throw std::invalid_argument("RH controller: control period must be > 0 s");
  qr_.compute(vandermonde(samples, std::min(samples - 1, kMaxDegree)));
}

Polynomial ExcitationFitter::fit(const Eigen::VectorXd& values) const {
  if (values.size() != samples_) throw std::invalid_argument("excitation fit: wrong number of samples");
  return Polynomial(qr_.solve(values));
}

std::shared_ptr<const plugin::ExcitationSignal> ExcitationFitter::signal(Polynomial fitted, double t0_s) const {
  return std::make_shared<PolynomialSignal>(std::move(fitted), t0_s, period_s_);
}

}  // namespace flatsos::planner
