#pragma once
// The whole-program NLP's start and its certificates (whole_program_nlp.hpp): a strictly feasible
// theta from two LPs on a grid, each moving constraint's block with its start factors and the
// start multipliers, and what the solution certifies.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "sos/whole_program_nlp.hpp"

namespace flatsos::planner::detail {

/// A point of the start LP's dual measure: constraint, scaled time s, weight.
struct StartDual {
  std::size_t constraint;
  double s, weight;
};

/// The highest power whose coefficient is not zero for every theta.
Eigen::Index structural_degree(const ConstraintPolynomial& c);
bool moves_with_theta(const ConstraintPolynomial& c);

/// On a grid of every segment, first the largest slack t (capped) with which every constraint can
/// hold, then the cheapest theta with half of it. Returns false (with a reason) when the grid
/// allows none.
bool strictly_feasible_start(const SosSetup& setup, const SosSettings& o, Eigen::VectorXd& theta,
                             std::vector<StartDual>& duals, std::string& why);

/// What theta cannot move is data: it must hold on its whole segment. Empty when it does.
std::string fixed_data_violation(const SosSetup& setup);

/// The blocks of the constraints theta moves, each scaled by its polynomial's size at the start,
/// and the NLP's start: theta, then each block's factors f and g.
struct WholeProgramStart {
  std::vector<SquaresBlock> blocks;
  std::vector<int> block_of;   ///< per constraint: its block, or -1
  std::vector<double> x;
  int equalities = 0;
};
WholeProgramStart blocks_from(const SosSetup& setup, const Eigen::VectorXd& theta_start);

/// The equalities' start multipliers from the start LP's dual measure.
Eigen::VectorXd start_multipliers(const WholeProgramStart& start, const std::vector<StartDual>& duals);

/// The certificates' residuals and the exact minima of every constraint at the solution.
void record_certificates(const SosSetup& setup, const std::vector<SquaresBlock>& blocks, const Eigen::VectorXd& solution,
                         const Eigen::VectorXd& theta, SosProgramResult& result);

}  // namespace flatsos::planner::detail
