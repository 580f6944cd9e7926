#include "flatsos/planner/effort.hpp"

#include <cmath>
#include <stdexcept>

namespace flatsos::planner {
namespace {

void require_weights(const Eigen::VectorXd& w, int muscles, const std::string& effort, bool allow_empty) {
  if (w.size() == 0 && allow_empty) return;
  if (w.size() != muscles)
    throw std::invalid_argument("effort '" + effort + "': needs one weight per muscle (" + std::to_string(muscles) +
                                "), got " + std::to_string(w.size()));
  for (Eigen::Index j = 0; j < w.size(); ++j)
    if (!(std::isfinite(w[j]) && w[j] >= 0.0))
      throw std::invalid_argument("effort '" + effort + "': weight " + std::to_string(j) + " must be finite and >= 0 (got " +
                                  std::to_string(w[j]) + ")");
  if (!(w.maxCoeff() > 0.0)) throw std::invalid_argument("effort '" + effort + "': every weight is 0: nothing to minimize");
}

// w x^p with its first two derivatives in x (x >= 0 in every use: bounds keep n, a >= 0 and
// F >= its reserve; |x| keeps the law defined and even elsewhere).
struct PowerJet {
  double value, slope, curvature;
};
PowerJet power(double w, double x, double p) {
  const double ax = std::abs(x), sign = x < 0.0 ? -1.0 : 1.0;
  if (p == 2.0) return {w * x * x, 2.0 * w * x, 2.0 * w};
  if (p == 1.0) return {w * ax, w * sign, 0.0};
  const double pm2 = std::pow(ax, p - 2.0);
  return {w * pm2 * ax * ax, w * p * pm2 * ax * sign, w * p * (p - 1.0) * pm2};
}

const char* quantity_name(PowerEffort::Quantity q) {
  switch (q) {
    case PowerEffort::Quantity::Excitation: return "excitation";
    case PowerEffort::Quantity::Activation: return "activation";
    case PowerEffort::Quantity::TendonStress: return "stress";
  }
  return "?";
}

}  // namespace

TendonForceEffort::TendonForceEffort(Eigen::VectorXd weights) : weights_(std::move(weights)) {}

void TendonForceEffort::validate(int muscles) const { require_weights(weights_, muscles, name(), false); }

MuscleEffortJet TendonForceEffort::muscleTerm(int j, const muscles::MuscleParameters&, double tendon_force_N, double,
                                              double) const {
  MuscleEffortJet t;
  t.value = weights_[j] * tendon_force_N;
  t.d_force = weights_[j];
  return t;
}

PowerEffort::PowerEffort(Quantity quantity, double exponent, Eigen::VectorXd weights)
    : quantity_(quantity), exponent_(exponent), weights_(std::move(weights)) {
  if (!(std::isfinite(exponent) && exponent >= 1.0))
    throw std::invalid_argument(std::string("effort on ") + quantity_name(quantity) + ": exponent must be >= 1 (got " +
                                std::to_string(exponent) + ")");
}

std::string PowerEffort::name() const {
  const std::string q = quantity_name(quantity_);
  if (exponent_ == 2.0) return q + "_squared";
  if (exponent_ == 3.0) return q + "_cubed";
  std::string p = std::to_string(exponent_);
  p.erase(p.find_last_not_of('0') + 1);
  if (!p.empty() && p.back() == '.') p.pop_back();
  return q + "_power_" + p;
}

void PowerEffort::validate(int muscles) const { require_weights(weights_, muscles, name(), true); }

MuscleEffortJet PowerEffort::muscleTerm(int j, const muscles::MuscleParameters& p, double tendon_force_N,
                                        double activation, double excitation) const {
  const double w = weights_.size() > 0 ? weights_[j] : 1.0;
  MuscleEffortJet t;
  switch (quantity_) {
    case Quantity::Excitation: {
      const PowerJet e = power(w, excitation, exponent_);
      t.value = e.value, t.d_excitation = e.slope, t.d_excitation2 = e.curvature;
      break;
    }
    case Quantity::Activation: {
      const PowerJet e = power(w, activation, exponent_);
      t.value = e.value, t.d_activation = e.slope, t.d_activation2 = e.curvature;
      break;
    }
    case Quantity::TendonStress: {  // x = F / Fmax
      const double fmax = p.max_isometric_force_N;
      const PowerJet e = power(w, tendon_force_N / fmax, exponent_);
      t.value = e.value, t.d_force = e.slope / fmax, t.d_force2 = e.curvature / (fmax * fmax);
      break;
    }
  }
  return t;
}

std::vector<std::string> effort_names() {
  return {"tendon_force",       "excitation_squared", "excitation_cubed", "activation_squared",
          "activation_cubed",   "stress_squared",     "stress_cubed"};
}

std::shared_ptr<const Effort> effort_named(const std::string& name, const Eigen::VectorXd& weights) {
  if (name == "tendon_force") return std::make_shared<TendonForceEffort>(weights);
  for (const PowerEffort::Quantity q :
       {PowerEffort::Quantity::Excitation, PowerEffort::Quantity::Activation, PowerEffort::Quantity::TendonStress})
    for (const double p : {2.0, 3.0}) {
      auto effort = std::make_shared<PowerEffort>(q, p, weights);
      if (effort->name() == name) return effort;
    }
  std::string known;
  for (const std::string& n : effort_names()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown effort '" + name + "' (known: " + known + ")");
}

}  // namespace flatsos::planner
