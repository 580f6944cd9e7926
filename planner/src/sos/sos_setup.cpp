#include "sos/sos_setup.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <Eigen/Dense>

namespace flatsos::planner::detail {

namespace {


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

}  // namespace

Eigen::RowVectorXd monomials(double s, Eigen::Index size) {
  Eigen::RowVectorXd v(size);
  double p = 1.0;
  for (Eigen::Index j = 0; j < size; ++j, p *= s) v[j] = p;
  return v;
}

SosSetup set_up_sos_program(const FlatOutputMap& flat, const TorqueModel& torque, double T, const FlatOutputBoundary& bc,
                            const Eigen::VectorXd& reserves, const SosProgramOptions& o) {
  const int m = flat.numMuscles(), n = flat.numJoints(), p = flat.numFlatOutputs();
  const int d = o.flat_output_degree;
  SosSetup setup;
  setup.duration_s = T;
  setup.degree = d;
  setup.torque = &torque;
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
  auto& outputs = setup.outputs;
  outputs.resize(static_cast<std::size_t>(p));
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
  auto& constraints = setup.constraints;
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
    // At t = 0 the initial state fixes the value; with a constant remainder bound the LP row
    // there carries it, with the vanishing bound (order 2) it is data, checked by fixed_violation.
    if (k == 0 && piece.remainder_order == 0) initial_points.insert(initial_points.begin(), 0.0);
    for (int j = 0; j < m; ++j) {
      ConstraintPolynomial c;
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
        c.base[piece.remainder_order] -= std::abs(Ctau(j, i)) * piece.remainder_N_m[i];
      }
      c.base[0] -= reserves[j];
      c.name = "tendon force of muscle '" + flat.model().description().muscles[static_cast<std::size_t>(j)].parameters.name + "'";
      c.reserve_N = reserves[j];
      c.margin_order = piece.remainder_order;
      for (int i = 0; i < n; ++i) c.remainder_cost_N += std::abs(Ctau(j, i)) * piece.remainder_N_m[i];
      c.points = initial_points;
      c.sticky.assign(initial_points.size(), false);
      constraints.push_back(std::move(c));
    }
    // Y = E F exactly (E C_tau = 0, E C_Y = I), so with E >= 0 entrywise and F >= reserve >= 0
    // the constraints Y >= 0 are implied and left out.
    for (int l = 0; l < p && !y_implied; ++l) {
      const auto& out = outputs[static_cast<std::size_t>(l)];
      ConstraintPolynomial c;
      c.piece = static_cast<int>(k);
      c.flat_output = l;
      c.name = "flat output '" + flat.model().description().flat_outputs[static_cast<std::size_t>(l)].name + "' >= 0";
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
  LinearProgram& lp = setup.lp;
  lp.cost = Eigen::VectorXd::Zero(n_theta);
  double& cost_constant = setup.cost_constant;
  for (const auto& out : outputs) {
    cost_constant += T * out.particular.dot(mean_weights);
    if (out.nullspace.cols()) lp.cost.segment(out.offset, out.nullspace.cols()) = T * out.nullspace.transpose() * mean_weights;
  }
  lp.x_lower = Eigen::VectorXd::Constant(n_theta, -o.study.coefficient_bound_N);
  lp.x_upper = Eigen::VectorXd::Constant(n_theta, o.study.coefficient_bound_N);

  setup.free_coefficients = n_theta;
  return setup;
}

std::string fixed_violation(const SosSetup& setup, double margin_N) {
  for (const auto& c : setup.constraints) {
    std::vector<double> where = c.points;
    if (c.piece == 0) where.push_back(0.0);  // t = 0, even where it is no LP point
    for (double s : where) {
      const Eigen::RowVectorXd v = monomials(s, c.base.size());
      const Eigen::RowVectorXd row = v * c.G;
      const double value = v.dot(c.base);
      // Eigen's maxCoeff on an empty vector is undefined: with no free coefficient (the
      // equalities fix Y completely) every row is fixed.
      const double row_size = row.size() ? row.cwiseAbs().maxCoeff() : 0.0;
      const double g_size = c.G.size() ? c.G.cwiseAbs().maxCoeff() : 0.0;
      if (row_size <= 1e-12 * (1.0 + g_size) && value < -margin_N) {
        const auto& piece = setup.torque->pieces[static_cast<std::size_t>(c.piece)];
        const double t = piece.t0_s + s * (piece.t1_s - piece.t0_s);
        std::ostringstream why;
        why << "infeasible: at t = " << t << " s the boundary conditions fix Y, and ";
        if (c.muscle >= 0)
          why << "the guaranteed " << c.name << " is " << -value << " N below its reserve of " << c.reserve_N
              << " N (the torque model's remainder bound costs " << c.remainder_cost_N * std::pow(s, piece.remainder_order)
              << " N there: use more pieces K or a higher degree r)";
        else
          why << c.name << " is violated by " << -value << " N";
        return why.str();
      }
    }
  }
  return "";
}

std::vector<Polynomial> flat_outputs_of(const SosSetup& setup, const Eigen::VectorXd& theta) {
  std::vector<Polynomial> Y;
  for (const auto& out : setup.outputs) {
    Eigen::VectorXd c_sigma = out.particular;
    if (out.nullspace.cols()) c_sigma += out.nullspace * theta.segment(out.offset, out.nullspace.cols());
    for (int j = 0; j <= setup.degree; ++j) c_sigma[j] /= std::pow(setup.duration_s, j);
    Y.emplace_back(c_sigma);
  }
  return Y;
}

}  // namespace flatsos::planner::detail
