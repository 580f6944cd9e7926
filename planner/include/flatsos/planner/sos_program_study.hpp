#pragma once
// The SOS program's study settings: second opinions, the reference formulation, iteration caps
// and tolerances. Their defaults are the measured choices the product plans with; tests,
// benchmarks and studies change them. The product (sos_program.hpp) does not include this header.

#include <string>

#include "flatsos/planner/sos_program.hpp"

namespace flatsos::planner {

/// The solver of the exchange LPs.
enum class ExchangeLpSolver {
  Simplex,  ///< Clp's dual simplex: a vertex to machine precision (the product's)
  Ipopt,    ///< the interior-point method, an independent second opinion
};

/// How the excitation bounds are imposed at their time points.
enum class BoundsSolver {
  SequentialLp,  ///< linearized bounds in a trust region, LPs by Clp (the product's)
  Ipopt,         ///< Ipopt, limited-memory Hessian (a second opinion)
};

/// How the reserves' program is solved.
enum class SosProgramMethod {
  Exchange,      ///< the exchange method, then certificates of the near-active pieces (the product's)
  /// The whole program as one Ipopt problem: theta and a single-square Markov-Lukacs certificate
  /// f^2 + s(1-s) g^2 of every constraint polynomial theta moves (the reference formulation,
  /// docs/method/whole_program_nlp.md). Excitation bounds are checked, not imposed.
  WholeProgramNlp,
};

/// "exchange" or "whole_program_nlp": the names the programs, summaries and Python use.
constexpr const char* to_string(SosProgramMethod m) {
  return m == SosProgramMethod::WholeProgramNlp ? "whole_program_nlp" : "exchange";
}
/// The method of that name; std::invalid_argument naming the accepted ones otherwise.
SosProgramMethod sos_program_method(const std::string& name);

/// Settings of the whole-program NLP.
struct WholeProgramOptions {
  double tolerance = 1e-10;  ///< Ipopt's tol and constr_viol_tol (the equalities are scaled to order 1)
  int max_iterations = 3000;
};

/// Settings of the exchange method's LPs.
struct ExchangeStudyOptions {
  ExchangeLpSolver lp_solver = ExchangeLpSolver::Simplex;
  double coefficient_bound_N = 1e7;    ///< |theta| box keeping early LPs bounded
  double prune_slack_N = 20.0;         ///< after an LP, initial points with more slack are dropped
  int initial_interior_points = 0;     ///< uniform points per segment imposed from the start, besides its end
};

/// Settings of the excitation bounds' exchange.
struct BoundsStudyOptions {
  BoundsSolver solver = BoundsSolver::SequentialLp;
  int check_points = 3001;           ///< the uniform grid on which the bounds hold
  double tolerance = 1e-8;           ///< allowed excess of a and n on that grid
  int initial_points_per_span = 1;   ///< uniform points imposed from the start (besides violators)
  /// Rounds of the bounded exchange (each solves at the points, then adds violated grid points).
  int max_rounds = 40;
  int max_sequential_lp_iterations = 200;      ///< sequential-LP steps per round
  int max_ipopt_iterations = 1000;   ///< BoundsSolver::Ipopt
};

struct SosProgramStudyOptions {
  SosProgramMethod method = SosProgramMethod::Exchange;
  WholeProgramOptions whole_program;
  double feasibility_margin_N = 1e-6;  ///< constraints are imposed >= this at the LP points
  int max_exchange_rounds = 40;
  bool certify = true;                 ///< Lukacs certificates for the near-active pieces
  double near_active_N = 1.0;          ///< pieces whose minimum is below this get certified
  ExchangeStudyOptions exchange;
  BoundsStudyOptions bounds;
};

/// solve_sos_program with study settings.
SosProgramResult solve_sos_program(const FlatOutputMap& flat, const TorqueModel& torque, double duration_s,
                                   const FlatOutputBoundary& boundary, const Eigen::VectorXd& reserves_N,
                                   const SosProgramOptions& options, const SosProgramStudyOptions& study,
                                   const MusclesAlongPath* muscles = nullptr);

}  // namespace flatsos::planner
