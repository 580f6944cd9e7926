#pragma once
// The SLP by Ipopt's interior-point method: an independent second opinion on the exact solvers
// of slp.hpp (the paper's solver; about 26 times the exact solver's time on the paper's arm).

#include <optional>

#include "flatsos/planner/slp.hpp"

namespace flatsos::planner {

/// Ipopt from `warm_start` (p entries; default: the appendix construction). If Ipopt fails, the
/// result falls back to the appendix construction (used_fallback, message says why). Throws as
/// solve_slp, and std::invalid_argument for a warm start of the wrong size or not finite.
SlpResult solve_slp_by_ipopt(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B,
                             const std::optional<Eigen::VectorXd>& warm_start = std::nullopt);
/// The same into `result` (Ipopt allocates inside).
void solve_slp_by_ipopt(const Eigen::MatrixXd& CY, const Eigen::VectorXd& B,
                        const std::optional<Eigen::VectorXd>& warm_start, SlpWorkspace& workspace, SlpResult& result);

}  // namespace flatsos::planner
