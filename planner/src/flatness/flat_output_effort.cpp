// The effort a FlatOutputMap's planners minimize: its weights, the effort seam (effort.hpp),
// and the weights its linear programs price forces with (tied muscles: tied_muscles.hpp).
#include <optional>
#include <stdexcept>

#include "flatness/tied_muscles.hpp"
#include "flatsos/planner/effort.hpp"
#include "flatsos/planner/flat_outputs.hpp"

namespace flatsos::planner {

void FlatOutputMap::setPricingWeights() {
  // The paper's E^T 1 prices flat outputs, not forces: the LPs use their sum as it is.
  pricing_weights_ = effortIsFlatOutputSum() ? effort_weights_ : detail::tie_broken_effort_weights(*model_, effort_weights_);
}

std::shared_ptr<const Effort> FlatOutputMap::effort() const {
  return std::make_shared<TendonForceEffort>(effort_weights_);
}

FlatOutputMap FlatOutputMap::withEffort(std::shared_ptr<const Effort> effort) const {
  if (!effort) throw std::invalid_argument("flat outputs: no effort given");
  effort->validate(muscles_);
  const std::optional<Eigen::VectorXd> weights = effort->tendonForceWeights();
  if (!weights)
    throw std::invalid_argument("effort '" + effort->name() +
                                "' is not linear in the tendon forces: the flatness planners minimize linear efforts "
                                "(w^T F); the collocation reference (collocation.hpp) minimizes any");
  FlatOutputMap out = *this;
  out.effort_weights_ = *weights;
  out.effort_kind_ = plugin::EffortWeights::Kind::PerMuscle;
  out.setPricingWeights();
  return out;
}

std::string FlatOutputMap::effortUnit() const {
  return effort_kind_ == plugin::EffortWeights::Kind::NormalizedTendonForce ? "s" : "N s";
}

bool FlatOutputMap::effortIsFlatOutputSum() const {
  return effort_kind_ == plugin::EffortWeights::Kind::FlatOutputs;
}

EffortSplit FlatOutputMap::effortSplit(const Eigen::VectorXd& q_rad) const {
  if (constant_) return {CY_.transpose() * effort_weights_, Ctau_.transpose() * effort_weights_};
  const ForceJetMap map = forceJetMap(q_rad);
  return {map.CY.transpose() * effort_weights_, map.Ctau.transpose() * effort_weights_};
}

}  // namespace flatsos::planner
