#pragma once
// The effort seam: what a plan minimizes, the integral over the motion of a sum over muscles
//   J = integral sum_j l_j(F_j, a_j, n_j) dt,
// each muscle's term separable in its tendon force F, activation a and excitation n. The
// flatness planners solve linear programs and need an effort linear in the tendon forces
// (tendonForceWeights): OpenLoopOptions::effort, or FlatOutputMap::withEffort for the
// receding-horizon step and controller; by default the model file's effort_weights
// (FlatOutputMap::effort). The collocation reference takes any effort with the first and second
// derivatives of its terms (CollocationOptions::effort). A new effort is one new implementation
// of this class.
//
// The efforts of the field:
//   TendonForceEffort  w^T F (N s): the paper's; its weights are the model file's effort_weights.
//   PowerEffort        sum_j w_j x_j^p with x = n (OpenSim Moco's MocoControlGoal, p = 2), x = a
//                      (static optimization's, p = 2 or 3) or x = F / Fmax (stress, p = 2 or 3);
//                      unit s. Unlike a linear effort it shares a load between synergists.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "flatsos/muscles/muscle_parameters.hpp"

namespace flatsos::planner {

/// One muscle's term l(F, a, n) with its first and (separable: no cross terms) second
/// derivatives.
struct MuscleEffortJet {
  double value = 0.0;
  double d_force = 0.0, d_activation = 0.0, d_excitation = 0.0;
  double d_force2 = 0.0, d_activation2 = 0.0, d_excitation2 = 0.0;
};

class Effort {
 public:
  virtual ~Effort() = default;
  /// The name the programs and model files use ("tendon_force", "excitation_squared", ...).
  virtual std::string name() const = 0;
  /// The unit of J: "N s" for a tendon-force effort, "s" for a dimensionless integrand.
  virtual std::string unit() const = 0;
  /// Throws std::invalid_argument naming the field when the effort does not fit `muscles`
  /// muscles (weights of another size).
  virtual void validate(int muscles) const = 0;
  /// w with sum_j l_j = w^T F when the effort is linear in the tendon forces (the flatness
  /// planners' linear programs need it), nothing otherwise.
  virtual std::optional<Eigen::VectorXd> tendonForceWeights() const { return std::nullopt; }
  /// l_j of muscle j (its parameters p) at (F, a, n).
  virtual MuscleEffortJet muscleTerm(int muscle, const muscles::MuscleParameters& p, double tendon_force_N,
                                     double activation, double excitation) const = 0;
};

/// w^T F: the paper's effort (weights >= 0, not all 0).
class TendonForceEffort final : public Effort {
 public:
  explicit TendonForceEffort(Eigen::VectorXd weights);
  std::string name() const override { return "tendon_force"; }
  std::string unit() const override { return "N s"; }
  void validate(int muscles) const override;
  std::optional<Eigen::VectorXd> tendonForceWeights() const override { return weights_; }
  MuscleEffortJet muscleTerm(int muscle, const muscles::MuscleParameters& p, double tendon_force_N, double activation,
                             double excitation) const override;

 private:
  Eigen::VectorXd weights_;
};

/// sum_j w_j x_j^p of one quantity x per muscle.
class PowerEffort final : public Effort {
 public:
  enum class Quantity { Excitation, Activation, TendonStress };
  /// p >= 1; weights >= 0 per muscle, or empty for 1 each.
  PowerEffort(Quantity quantity, double exponent, Eigen::VectorXd weights = {});
  /// "excitation_squared", "activation_cubed", "stress_squared", ... (p = 2, 3), else
  /// "excitation_power_<p>".
  std::string name() const override;
  std::string unit() const override { return "s"; }
  void validate(int muscles) const override;
  MuscleEffortJet muscleTerm(int muscle, const muscles::MuscleParameters& p, double tendon_force_N, double activation,
                             double excitation) const override;
  Quantity quantity() const { return quantity_; }
  double exponent() const { return exponent_; }

 private:
  Quantity quantity_;
  double exponent_;
  Eigen::VectorXd weights_;
};

/// The effort a name gives (effort_names()), weighted per muscle by `weights` (empty: each 1;
/// "tendon_force" needs them). Throws std::invalid_argument listing the names for another.
std::shared_ptr<const Effort> effort_named(const std::string& name, const Eigen::VectorXd& weights = {});
/// "tendon_force", "excitation_squared", "excitation_cubed", "activation_squared",
/// "activation_cubed", "stress_squared", "stress_cubed".
std::vector<std::string> effort_names();

}  // namespace flatsos::planner
