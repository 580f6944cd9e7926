#pragma once
// The receding-horizon step's study settings: Ipopt as the SLP's solver (the paper's, a second
// opinion on the exact solvers) and the bounds' iteration cap. The defaults are the product's.

#include <optional>

#include "flatsos/planner/receding_horizon_step.hpp"

namespace flatsos::planner {

struct RecedingHorizonStudyOptions {
  bool slp_by_ipopt = false;                  ///< solve the SLP by Ipopt (slp_study.hpp)
  std::optional<Eigen::VectorXd> warm_start;  ///< Ipopt's start (e.g. the last alpha), p entries
  int bound_max_iterations = 100;             ///< LP steps of the excitation bounds' sequential LP
};

/// plan_receding_horizon_step with study settings; also throws std::invalid_argument for a warm
/// start of the wrong size or a bound_max_iterations below 1.
void plan_receding_horizon_step(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace,
                                const Eigen::VectorXd& q_rad, const Eigen::VectorXd& qd_rad_per_s,
                                const RecedingHorizonOptions& options, const RecedingHorizonStudyOptions& study,
                                RecedingHorizonStep& step);
RecedingHorizonStep plan_receding_horizon_step(const FlatOutputMap& flat, const Eigen::VectorXd& q_rad,
                                               const Eigen::VectorXd& qd_rad_per_s, const RecedingHorizonOptions& options,
                                               const RecedingHorizonStudyOptions& study);

}  // namespace flatsos::planner
