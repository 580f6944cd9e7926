#include "flatsos/planner/sos_program.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <Eigen/Dense>

#include "flatsos/planner/numerics/small_lp.hpp"
#include "flatsos/planner/numerics/sos_certificate.hpp"

namespace flatsos::planner {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
constexpr double kNoBound = 1e19;

// One constraint polynomial on one piece, affine in theta: coefficients (in s) = base + G theta.
struct AffinePolynomial {
  Eigen::VectorXd base;
  Eigen::MatrixXd G;
  int piece = 0;
  int muscle = -1;       ///< >= 0: tendon-force constraint of this muscle
  int flat_output = -1;  ///< >= 0: Y_l >= 0
  std::vector<double> points;
  std::vector<bool> sticky;  ///< added by the exchange: never pruned
  Polynomial at(const Eigen::VectorXd& theta) const { return Polynomial(base + G * theta); }
};

// Y_l = c_p + N theta_l in the global scaled time sigma = t / T.
struct OutputParameterization {
  Eigen::VectorXd particular;
  Eigen::MatrixXd nullspace;
  int offset = 0;
};

Eigen::RowVectorXd monomials(double s, Eigen::Index size) {
  Eigen::RowVectorXd v(size);
  double p = 1.0;
  for (Eigen::Index j = 0; j < size; ++j, p *= s) v[j] = p;
  return v;
}

// Rows of the equality "derivative k of Y at sigma0 equals value" in sigma-coefficients.
void add_derivative_rows(Eigen::MatrixXd& A, Eigen::VectorXd& b, Eigen::Index& row, int degree, double sigma0,
                         int first_order, const Eigen::RowVectorXd& values, double T) {
  for (Eigen::Index k = 0; k < values.size(); ++k, ++row) {
    const int order = first_order + static_cast<int>(k);
    for (int j = order; j <= degree; ++j) {
      double falling = 1.0;
      for (int i = 0; i < order; ++i) falling *= j - i;
      A(row, j) = falling * std::pow(sigma0, j - order);
    }
    b[row] = values[k] * std::pow(T, order);  // d^k/dsigma^k = T^k d^k/dt^k
  }
}

std::string describe(const AffinePolynomial& c, const FlatOutputMap& flat) {
  if (c.muscle >= 0) return "tendon force of muscle '" + flat.model().description().muscles[c.muscle].parameters.name + "'";
  return "flat output '" + flat.model().description().flat_outputs[c.flat_output].name + "' >= 0";
}

}  // namespace

SosProgramResult solve_sos_program(const FlatOutputMap& flat, const TorqueModel& torque, double T,
                                   const FlatOutputBoundary& bc, const Eigen::VectorXd& reserves,
                                   const SosProgramOptions& o) {
  const auto t_setup = Clock::now();
  const int m = flat.numMuscles(), n = flat.numJoints(), p = flat.numFlatOutputs();
  const int d = o.flat_output_degree;
  if (!(T > 0.0) || !std::isfinite(T)) throw std::invalid_argument("SOS program: horizon T must be > 0 s");
  if (d < 0) throw std::invalid_argument("SOS program: flat-output degree must be >= 0");
  if (reserves.size() != m || !reserves.allFinite() || reserves.minCoeff() < 0.0)
    throw std::invalid_argument("SOS program: reserves must be " + std::to_string(m) + " finite forces >= 0 N");
  if ((bc.initial.size() && bc.initial.rows() != p) || (bc.terminal.size() && bc.terminal.rows() != p))
    throw std::invalid_argument("SOS program: boundary conditions must have one row per flat output (" +
                                std::to_string(p) + ")");
  if (!bc.initial.allFinite() || !bc.terminal.allFinite())
    throw std::invalid_argument("SOS program: boundary conditions must be finite");
  if (torque.pieces.empty()) throw std::invalid_argument("SOS program: empty torque model");
  const int n_eq = static_cast<int>(bc.initial.cols() + bc.terminal.cols());
  if (n_eq > d + 1)
    throw std::invalid_argument("SOS program: flat-output degree " + std::to_string(d) + " is too low for " +
                                std::to_string(n_eq) + " boundary equalities (needs >= " + std::to_string(n_eq - 1) + ")");

  // --- eliminate the boundary equalities: Y_l = c_p + N theta_l ---
  std::vector<OutputParameterization> outputs(static_cast<std::size_t>(p));
  int n_theta = 0;
  for (int l = 0; l < p; ++l) {
    Eigen::MatrixXd Aeq = Eigen::MatrixXd::Zero(n_eq, d + 1);
    Eigen::VectorXd beq(n_eq);
    Eigen::Index row = 0;
    if (bc.initial.cols()) add_derivative_rows(Aeq, beq, row, d, 0.0, 0, bc.initial.row(l), T);
    if (bc.terminal.cols()) add_derivative_rows(Aeq, beq, row, d, 1.0, bc.terminal_first_order, bc.terminal.row(l), T);
    auto& out = outputs[static_cast<std::size_t>(l)];
    if (n_eq == 0) {
      out.particular = Eigen::VectorXd::Zero(d + 1);
      out.nullspace = Eigen::MatrixXd::Identity(d + 1, d + 1);
    } else {
      Eigen::FullPivLU<Eigen::MatrixXd> lu(Aeq);
      if (lu.rank() < n_eq)
        throw std::invalid_argument("SOS program: the boundary equalities on Y are dependent for this degree");
      out.particular = lu.solve(beq);
      out.nullspace = lu.kernel();
      if (out.nullspace.cols() == 1 && out.nullspace.isZero()) out.nullspace.resize(d + 1, 0);
    }
    out.offset = n_theta;
    n_theta += static_cast<int>(out.nullspace.cols());
  }

  // --- constraint polynomials per piece, in the piece's scaled time ---
  int r = 0;
  for (const auto& piece : torque.pieces)
    for (const auto& poly : piece.torque) r = std::max(r, poly.degree());
  const int D = std::max(d, r);
  std::vector<AffinePolynomial> constraints;
  const bool y_implied = flat.E().minCoeff() >= 0.0;
  const Eigen::MatrixXd& Ctau = flat.Ctau();
  const Eigen::MatrixXd& CY = flat.CY();
  for (std::size_t k = 0; k < torque.pieces.size(); ++k) {
    const TorquePiece& piece = torque.pieces[k];
    const double a = piece.t0_s / T, b = (piece.t1_s - piece.t0_s) / T;
    Eigen::MatrixXd P = Eigen::MatrixXd::Zero(D + 1, d + 1);  // sigma-coefficients -> s-coefficients
    for (int j = 0; j <= d; ++j) {
      Eigen::VectorXd e = Eigen::VectorXd::Zero(j + 1);
      e[j] = 1.0;
      P.col(j).head(j + 1) = Polynomial(e).composeAffine(a, b).coefficients();
    }
    // Piece ends only: the exchange adds interior minima where they are violated.
    std::vector<double> initial_points = {1.0};
    if (k == 0) initial_points.insert(initial_points.begin(), 0.0);
    for (int j = 0; j < m; ++j) {
      AffinePolynomial c;
      c.piece = static_cast<int>(k);
      c.muscle = j;
      c.base = Eigen::VectorXd::Zero(D + 1);
      c.G = Eigen::MatrixXd::Zero(D + 1, n_theta);
      for (int l = 0; l < p; ++l) {
        const auto& out = outputs[static_cast<std::size_t>(l)];
        c.base += CY(j, l) * P * out.particular;
        c.G.middleCols(out.offset, out.nullspace.cols()) += CY(j, l) * P * out.nullspace;
      }
      for (int i = 0; i < n; ++i) {
        const Eigen::VectorXd& tc = piece.torque[static_cast<std::size_t>(i)].coefficients();
        c.base.head(tc.size()) += Ctau(j, i) * tc;
        c.base[0] -= std::abs(Ctau(j, i)) * piece.remainder_N_m[i];
      }
      c.base[0] -= reserves[j];
      c.points = initial_points;
      c.sticky.assign(initial_points.size(), false);
      constraints.push_back(std::move(c));
    }
    // Y = E F exactly (E C_tau = 0, E C_Y = I), so with E >= 0 entrywise and F >= reserve >= 0
    // the constraints Y >= 0 are implied and left out.
    for (int l = 0; l < p && !y_implied; ++l) {
      const auto& out = outputs[static_cast<std::size_t>(l)];
      AffinePolynomial c;
      c.piece = static_cast<int>(k);
      c.flat_output = l;
      c.base = P * out.particular;
      c.G = Eigen::MatrixXd::Zero(D + 1, n_theta);
      c.G.middleCols(out.offset, out.nullspace.cols()) = P * out.nullspace;
      c.points = initial_points;
      c.sticky.assign(initial_points.size(), false);
      constraints.push_back(std::move(c));
    }
  }

  // --- cost: T * integral_0^1 sum_l Y_l(sigma) dsigma ---
  Eigen::VectorXd mean_weights(d + 1);
  for (int j = 0; j <= d; ++j) mean_weights[j] = 1.0 / (j + 1);
  LinearProgram lp;
  lp.cost = Eigen::VectorXd::Zero(n_theta);
  double cost_constant = 0.0;
  for (const auto& out : outputs) {
    cost_constant += T * out.particular.dot(mean_weights);
    if (out.nullspace.cols()) lp.cost.segment(out.offset, out.nullspace.cols()) = T * out.nullspace.transpose() * mean_weights;
  }
  lp.x_lower = Eigen::VectorXd::Constant(n_theta, -o.coefficient_bound_N);
  lp.x_upper = Eigen::VectorXd::Constant(n_theta, o.coefficient_bound_N);

  SosProgramResult result;
  result.setup_seconds = seconds_since(t_setup);
  const auto t_solve = Clock::now();

  auto build_rows = [&]() {
    std::size_t rows = 0;
    for (const auto& c : constraints) rows += c.points.size();
    lp.G.resize(static_cast<Eigen::Index>(rows), n_theta);
    lp.row_lower.resize(static_cast<Eigen::Index>(rows));
    lp.row_upper = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(rows), kNoBound);
    Eigen::Index row = 0;
    for (const auto& c : constraints)
      for (double s : c.points) {
        const Eigen::RowVectorXd v = monomials(s, c.base.size());
        lp.G.row(row) = v * c.G;
        lp.row_lower[row] = o.feasibility_margin_N - v.dot(c.base);
        ++row;
      }
    result.lp_points = static_cast<int>(rows);
  };

  // Constraints that no free coefficient can change (the boundary equalities fix Y there):
  // if one is violated, the program is infeasible for a reason we can name.
  auto fixed_violation = [&]() -> std::string {
    for (const auto& c : constraints)
      for (double s : c.points) {
        const Eigen::RowVectorXd v = monomials(s, c.base.size());
        const Eigen::RowVectorXd row = v * c.G;
        const double value = v.dot(c.base);
        // Eigen's maxCoeff on an empty vector is undefined: with no free coefficient (the
        // equalities fix Y completely) every row is fixed.
        const double row_size = row.size() ? row.cwiseAbs().maxCoeff() : 0.0;
        const double g_size = c.G.size() ? c.G.cwiseAbs().maxCoeff() : 0.0;
        if (row_size <= 1e-12 * (1.0 + g_size) && value < -o.feasibility_margin_N) {
          const auto& piece = torque.pieces[static_cast<std::size_t>(c.piece)];
          const double t = piece.t0_s + s * (piece.t1_s - piece.t0_s);
          std::ostringstream why;
          why << "infeasible: at t = " << t << " s the boundary conditions fix Y, and ";
          if (c.muscle >= 0) {
            double margin = 0.0;
            for (int i = 0; i < n; ++i) margin += std::abs(Ctau(c.muscle, i)) * piece.remainder_N_m[i];
            why << "the guaranteed " << describe(c, flat) << " is " << -value << " N below its reserve of "
                << reserves[c.muscle] << " N (the torque model's remainder bound costs " << margin
                << " N there: use more pieces K or a higher degree r)";
          } else {
            why << describe(c, flat) << " is violated by " << -value << " N";
          }
          return why.str();
        }
      }
    return "";
  };

  if (const std::string reason = fixed_violation(); !reason.empty()) {
    result.status = SolveStatus::Infeasible;
    result.message = reason;
    result.solve_seconds = seconds_since(t_solve);
    return result;
  }
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(n_theta);
  bool converged = false;
  // Ipopt solves an exchange LP when the exact solver cannot, and always the final one: the
  // reported optimum is Ipopt's.
  auto ipopt_round = [&](int round) -> bool {
    LinearProgramOptions lpo;
    if (round > 0 || o.exact_exchange) lpo.start = theta;
    const LinearProgramResult lr = solve_linear_program(lp, lpo);
    result.ipopt_iterations += lr.iterations;
    ++result.ipopt_calls;
    if (lr.status != SolveStatus::Solved) {
      const std::string reason = fixed_violation();
      result.status = lr.status == SolveStatus::Infeasible || !reason.empty() ? SolveStatus::Infeasible : SolveStatus::Failed;
      result.message = !reason.empty() ? reason
                                       : "the exchange LP of round " + std::to_string(round + 1) +
                                             " was not solved (Ipopt: " + lr.solver_status + ")";
      result.solve_seconds = seconds_since(t_solve);
      return false;
    }
    theta = lr.x;
    return true;
  };
  bool last_by_ipopt = false;
  for (int round = 0; round < o.max_exchange_rounds; ++round) {
    result.exchange_rounds = round + 1;
    if (n_theta > 0) {
      build_rows();
      SmallLpResult exact;
      if (o.exact_exchange) {
        exact = solve_small_lp(lp);
        result.exact_lp_pivots += exact.pivots;
      }
      if (exact.status == SolveStatus::Solved) {
        theta = exact.x;
        last_by_ipopt = false;
      } else {
        if (!ipopt_round(round)) return result;
        last_by_ipopt = true;
      }
      // Keep the LPs small: initial points far from active leave the next LP (Ipopt's cost per
      // iteration grows with the rows). A pruned constraint that becomes violated is caught by
      // the exact minimum below and comes back as a sticky point.
      for (auto& c : constraints) {
        const Polynomial g = c.at(theta);
        for (std::size_t i = c.points.size(); i-- > 0;)
          if (!c.sticky[i] && g(c.points[i]) > o.prune_slack_N) {
            c.points.erase(c.points.begin() + static_cast<std::ptrdiff_t>(i));
            c.sticky.erase(c.sticky.begin() + static_cast<std::ptrdiff_t>(i));
          }
      }
    }
    // Exact minimum of every constraint polynomial; add the violated points.
    auto add_violated = [&]() {
      bool added = false;
      result.min_constraint_value_N = kNoBound;
      for (auto& c : constraints) {
        const IntervalMinimum mn = minimum_on_interval(c.at(theta), 0.0, 1.0);
        result.min_constraint_value_N = std::min(result.min_constraint_value_N, mn.value);
        if (mn.value < 0.0) {
          const bool known = std::any_of(c.points.begin(), c.points.end(), [&](double s) { return std::abs(s - mn.at) < 1e-9; });
          if (!known) {
            c.points.push_back(mn.at);
            c.sticky.push_back(true);
            added = true;
          }
        }
      }
      return added;
    };
    if (add_violated()) continue;
    if (n_theta > 0 && !last_by_ipopt) {
      // The exact solver converged: Ipopt solves the final LP (on the final points, started there).
      build_rows();
      if (!ipopt_round(round)) return result;
      last_by_ipopt = true;
      if (add_violated()) continue;
    }
    converged = true;
    break;
  }
  result.solve_seconds = seconds_since(t_solve);

  if (const std::string reason = fixed_violation(); !reason.empty()) {
    result.status = SolveStatus::Infeasible;
    result.message = reason;
    return result;
  }
  if (!converged || result.min_constraint_value_N < -1e-6) {
    result.status = SolveStatus::Failed;
    std::ostringstream why;
    why << "the exchange method did not converge in " << o.max_exchange_rounds << " rounds (worst constraint value "
        << result.min_constraint_value_N << " N)";
    result.message = why.str();
    return result;
  }
  if (n_theta > 0 && (theta.cwiseAbs().maxCoeff() > 0.999 * o.coefficient_bound_N)) {
    result.status = SolveStatus::Failed;
    result.message = "the SOS program is unbounded: a free coefficient of Y reached the bound " +
                     std::to_string(o.coefficient_bound_N) + " N";
    return result;
  }

  // --- the plan: Y in seconds, cost ---
  result.cost_N_s = cost_constant + lp.cost.dot(theta);
  for (const auto& out : outputs) {
    Eigen::VectorXd c_sigma = out.particular;
    if (out.nullspace.cols()) c_sigma += out.nullspace * theta.segment(out.offset, out.nullspace.cols());
    for (int j = 0; j <= d; ++j) c_sigma[j] /= std::pow(T, j);
    result.Y.emplace_back(c_sigma);
  }
  result.status = SolveStatus::Solved;

  // --- Lukacs certificates for the pieces that come near zero ---
  if (o.certify) {
    const auto t_cert = Clock::now();
    std::vector<Polynomial> near_active;
    for (const auto& c : constraints) {
      const Polynomial g = c.at(theta);
      if (minimum_on_interval(g, 0.0, 1.0).value < o.near_active_N) near_active.push_back(g);
    }
    result.near_active_pieces = static_cast<int>(near_active.size());
    if (near_active.empty()) {
      result.certified = true;
    } else {
      const CertificationResult cert = certify_nonnegative_on_unit_interval(near_active, 1e-9);
      result.certified_pieces = static_cast<int>(std::count(cert.certified.begin(), cert.certified.end(), true));
      result.certified = cert.all_certified;
      result.ipopt_iterations += cert.ipopt_iterations;
      result.ipopt_calls += cert.ipopt_calls;
    }
    result.certify_seconds = seconds_since(t_cert);
  }
  return result;
}

}  // namespace flatsos::planner
