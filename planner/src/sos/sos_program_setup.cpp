#include "sos/sos_setup.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

namespace flatsos::planner::detail {

namespace {

// Column j: the coefficients of (a + b s)^j in powers of s (size x size).
Eigen::MatrixXd affine_composition(int size, double a, double b) {
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(size, size);
  for (int j = 0; j < size; ++j) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(j + 1);
    e[j] = 1.0;
    P.col(j).head(j + 1) = Polynomial(e).composeAffine(a, b).coefficients();
  }
  return P;
}

// Breakpoints of the common refinement of the torque pieces and the spline spans.
std::vector<double> segment_breaks(const TorqueModel& torque, const BSplineBasis& basis) {
  std::vector<double> breaks;
  for (const auto& piece : torque.pieces) breaks.push_back(piece.t0_s);
  breaks.insert(breaks.end(), basis.breakpoints().begin(), basis.breakpoints().end());
  std::sort(breaks.begin(), breaks.end());
  const double tolerance = 1e-12 * basis.duration();
  breaks.erase(std::unique(breaks.begin(), breaks.end(), [&](double x, double y) { return y - x <= tolerance; }),
               breaks.end());
  return breaks;
}

// The matrix that multiplies a polynomial's coefficients (in_size of them) by c's: column i holds
// c shifted down by i (out_size rows, enough for the product).
Eigen::MatrixXd product_matrix(const Eigen::VectorXd& c, Eigen::Index in_size, Eigen::Index out_size) {
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(out_size, in_size);
  for (Eigen::Index i = 0; i < in_size; ++i)
    for (Eigen::Index k = 0; k < c.size(); ++k) M(i + k, i) = c[k];
  return M;
}

int piece_at(const TorqueModel& torque, double t) {
  for (std::size_t k = 0; k < torque.pieces.size(); ++k)
    if (t < torque.pieces[k].t1_s) return static_cast<int>(k);
  return static_cast<int>(torque.pieces.size()) - 1;
}

void require_valid_inputs(const FlatOutputMap& flat, const TorqueModel& torque, double T, const FlatOutputBoundary& bc,
                          const Eigen::VectorXd& reserves, const SosSettings& o) {
  const int m = flat.numMuscles(), p = flat.numFlatOutputs();
  if (!(T > 0.0) || !std::isfinite(T)) throw std::invalid_argument("SOS program: horizon T must be > 0 s");
  if (o.flat_output_degree < 1) throw std::invalid_argument("SOS program: flat-output degree must be >= 1");
  if (o.flat_output_spans < 1) throw std::invalid_argument("SOS program: flat outputs need at least 1 span");
  if (!(o.flat_output_span_growth > 0.0) || !std::isfinite(o.flat_output_span_growth))
    throw std::invalid_argument("SOS program: flat_output_span_growth must be finite and > 0 (1: uniform spans)");
  if (reserves.size() != m || !reserves.allFinite() || reserves.minCoeff() < 0.0)
    throw std::invalid_argument("SOS program: reserves must be " + std::to_string(m) + " finite forces >= 0 N");
  if ((bc.initial.size() && bc.initial.rows() != p) || (bc.terminal.size() && bc.terminal.rows() != p))
    throw std::invalid_argument("SOS program: boundary conditions must have one row per flat output (" +
                                std::to_string(p) + ")");
  if (!bc.initial.allFinite() || !bc.terminal.allFinite())
    throw std::invalid_argument("SOS program: boundary conditions must be finite");
  if (torque.pieces.empty()) throw std::invalid_argument("SOS program: empty torque model");
  const int n_eq = static_cast<int>(bc.initial.cols() + bc.terminal.cols());
  const int size = o.flat_output_degree + o.flat_output_spans;
  if (n_eq > size)
    throw std::invalid_argument("SOS program: flat-output degree " + std::to_string(o.flat_output_degree) + " with " +
                                std::to_string(o.flat_output_spans) + " span(s) is too low for " + std::to_string(n_eq) +
                                " boundary equalities (needs degree + spans >= " + std::to_string(n_eq) + ")");
}

// One segment of the common refinement of torque pieces and spline spans, and both scaled times
// as affine functions of the segment's s: s_piece = a + b s, s_span = as + bs s.
struct Segment {
  double t0 = 0.0, t1 = 0.0;
  int piece_index = 0;
  const TorquePiece* piece = nullptr;
  double a = 0.0, b = 1.0;
  Eigen::MatrixXd P;              // Y's B-spline coefficients -> powers of s (D + 1 rows)
  Polynomial remainder_shape;     // s_piece^order as a polynomial of s: (a + b s)^order
  int margin_order = 0;
  std::vector<double> initial_points;
};

// The SOS program's setup (sos_setup.hpp, set_up_sos_program): the boundary equalities
// eliminated, then per segment the constraint polynomials and the cost.
class SetupBuilder {
 public:
  SetupBuilder(const FlatOutputMap& flat, const TorqueModel& torque, double T, const FlatOutputBoundary& bc,
               const Eigen::VectorXd& reserves, const SosSettings& o)
      : flat_(flat), torque_(torque), bc_(bc), reserves_(reserves), o_(o), m_(flat.numMuscles()), n_(flat.numJoints()),
        p_(flat.numFlatOutputs()), d_(o.flat_output_degree), varying_(!flat.hasConstantMomentArms()),
        setup_(T, BSplineBasis::geometric(o.flat_output_degree, o.flat_output_spans, T, o.flat_output_span_growth)) {}

  SosSetup build() {
    setup_.torque = &torque_;
    eliminateEqualities();
    chooseDegree();
    // Y = E F exactly (E C_tau = 0, E C_Y = I), so with E >= 0 entrywise and F >= reserve >= 0
    // the constraints Y >= 0 are implied and left out; the coupling's bound needs them imposed.
    const bool y_implied = !varying_ && flat_.E().minCoeff() >= 0.0;
    setup_.lp.cost = Eigen::VectorXd::Zero(n_theta_);
    setup_.effort_cost = Eigen::VectorXd::Zero(n_theta_);
    const Eigen::VectorXd& effort_weights = flat_.effortWeights();
    // The LP prices tied muscles apart (FlatOutputMap::effortPricingWeights); the effort
    // reported is the model's.
    const Eigen::VectorXd& lp_weights = flat_.effortPricingWeights();
    const bool priced_apart = lp_weights != effort_weights;  // else one cost serves both
    const CostWeights lp_cost{lp_weights, splitOf(lp_weights), setup_.lp.cost, setup_.cost_constant};
    const CostWeights effort_cost{effort_weights, splitOf(effort_weights), setup_.effort_cost,
                                  setup_.effort_cost_constant};
    const std::vector<double> breaks = segment_breaks(torque_, setup_.basis);
    for (std::size_t seg = 0; seg + 1 < breaks.size(); ++seg) {
      const Segment s = segment(breaks[seg], breaks[seg + 1], seg == 0);
      for (int j = 0; j < m_; ++j) add(s, tendonForceConstraint(s, j));
      for (int l = 0; l < p_ && !y_implied; ++l) add(s, flatOutputConstraint(s, l));
      addCost(s, lp_cost);
      if (priced_apart) addCost(s, effort_cost);
    }
    if (!priced_apart) {
      setup_.effort_cost = setup_.lp.cost;
      setup_.effort_cost_constant = setup_.cost_constant;
    }
    setup_.lp.x_lower = Eigen::VectorXd::Constant(n_theta_, -o_.exchange.coefficient_bound_N);
    setup_.lp.x_upper = Eigen::VectorXd::Constant(n_theta_, o_.exchange.coefficient_bound_N);
    setup_.free_coefficients = n_theta_;
    return std::move(setup_);
  }

 private:
  void eliminateEqualities() {
    for (int l = 0; l < p_; ++l) {
      setup_.outputs.push_back(eliminate_equalities(setup_.basis, bc_, l));
      setup_.outputs.back().offset = n_theta_;
      n_theta_ += static_cast<int>(setup_.outputs.back().nullspace.cols());
    }
  }

  // The constraint polynomials' degree D in the segment's scaled time. With posture-dependent
  // moment arms each tendon force is b_j + sum_l c_jl Y_l with modelled b_j and c_jl; where
  // Y_l >= 0, c_jl Y_l >= (c_jl's polynomial - its remainder bound) Y_l: a polynomial of degree
  // d + r, still affine in theta.
  void chooseDegree() {
    if (varying_)
      for (const auto& piece : torque_.pieces)
        if (piece.coupling.size() != static_cast<std::size_t>(m_ * p_))
          throw std::invalid_argument("SOS program: the torque model has no coupling model for this model's posture-dependent "
                                      "moment arms (build it with this flat-output map)");
    int r = 2;  // the first piece's remainder bound is quadratic
    int coupling_degree = 0;
    for (const auto& piece : torque_.pieces) {
      for (const auto& poly : piece.torque) r = std::max(r, poly.degree());
      for (const auto& poly : piece.base_force) r = std::max(r, poly.degree());
      if (!varying_) continue;
      coupling_degree = std::max(coupling_degree, piece.remainder_order);
      for (const auto& poly : piece.coupling) coupling_degree = std::max(coupling_degree, poly.degree());
    }
    D_ = std::max(d_ + coupling_degree, r);
    mean_weights_.resize(D_ + 1);  // integral over [0, 1] of s^j
    for (int j = 0; j <= D_; ++j) mean_weights_[j] = 1.0 / (j + 1);
  }

  Segment segment(double t0, double t1, bool starts_at_zero) const {
    const BSplineBasis& basis = setup_.basis;
    Segment s;
    s.t0 = t0;
    s.t1 = t1;
    const double mid = 0.5 * (t0 + t1);
    s.piece_index = piece_at(torque_, mid);
    s.piece = &torque_.pieces[static_cast<std::size_t>(s.piece_index)];
    const int span = basis.spanAt(mid);
    s.b = (t1 - t0) / (s.piece->t1_s - s.piece->t0_s);
    s.a = (t0 - s.piece->t0_s) / (s.piece->t1_s - s.piece->t0_s);
    const double h = basis.spanLength(span);
    const double bs = (t1 - t0) / h, as = (t0 - basis.spanStart(span)) / h;
    s.P = Eigen::MatrixXd::Zero(D_ + 1, basis.size());
    s.P.topRows(d_ + 1) = affine_composition(d_ + 1, as, bs) * basis.spanPowerMatrix(span);
    const int order = s.piece->remainder_order;
    s.remainder_shape = Polynomial(affine_composition(order + 1, s.a, s.b).col(order));
    s.margin_order = starts_at_zero ? order : 0;
    // At t = 0 the initial state fixes the value; with a constant remainder bound the LP row
    // there carries it, with the vanishing bound (order 2) it is data, checked by fixed_violation.
    const int interior = o_.exchange.initial_interior_points;  // the exchange adds interior minima where violated
    for (int i = 1; i <= interior; ++i) s.initial_points.push_back(i / (interior + 1.0));
    s.initial_points.push_back(1.0);
    if (starts_at_zero && s.margin_order == 0) s.initial_points.insert(s.initial_points.begin(), 0.0);
    return s;
  }

  void add(const Segment& s, ConstraintPolynomial c) {
    c.t0_s = s.t0;
    c.t1_s = s.t1;
    c.piece = s.piece_index;
    c.margin_order = s.margin_order;
    c.points = s.initial_points;
    c.sticky.assign(s.initial_points.size(), false);
    setup_.constraints.push_back(std::move(c));
  }

  ConstraintPolynomial tendonForceConstraint(const Segment& s, int j) const {
    ConstraintPolynomial c;
    c.muscle = j;
    c.base = Eigen::VectorXd::Zero(D_ + 1);
    c.G = Eigen::MatrixXd::Zero(D_ + 1, n_theta_);
    if (varying_) addVaryingForce(s, j, c);
    else addConstantForce(s, j, c);
    c.base[0] -= reserves_[j];
    c.name = "tendon force of muscle '" + flat_.model().description().muscles[static_cast<std::size_t>(j)].parameters.name + "'";
    c.reserve_N = reserves_[j];
    return c;
  }

  // sum_l (c_jl - e_jl s^order) Y_l + b_j - e_bj s^order.
  void addVaryingForce(const Segment& s, int j, ConstraintPolynomial& c) const {
    const TorquePiece& piece = *s.piece;
    const Eigen::VectorXd& shape = s.remainder_shape.coefficients();
    Eigen::VectorXd remainder_cost = piece.base_force_remainder_N[j] * shape;
    remainder_cost.conservativeResize(D_ + 1);
    remainder_cost.tail(D_ + 1 - shape.size()).setZero();
    const Eigen::MatrixXd Yl = s.P.topRows(d_ + 1);
    for (int l = 0; l < p_; ++l) {
      const auto& out = setup_.outputs[static_cast<std::size_t>(l)];
      const std::size_t jl = static_cast<std::size_t>(j * p_ + l);
      const Polynomial lower = piece.coupling[jl].composeAffine(s.a, s.b) - s.remainder_shape * piece.coupling_remainder[jl];
      const Eigen::MatrixXd times_lower = product_matrix(lower.coefficients(), d_ + 1, D_ + 1);
      c.base += times_lower * (Yl * out.particular);
      c.G.middleCols(out.offset, out.nullspace.cols()) += times_lower * (Yl * out.nullspace);
      // What the coupling's remainder costs with Y at its particular part (exact when Y is fixed).
      remainder_cost += product_matrix(shape * piece.coupling_remainder[jl], d_ + 1, D_ + 1) * (Yl * out.particular);
    }
    const Eigen::VectorXd bc_poly = piece.base_force[static_cast<std::size_t>(j)].composeAffine(s.a, s.b).coefficients();
    c.base.head(bc_poly.size()) += bc_poly;
    c.base.head(shape.size()) -= piece.base_force_remainder_N[j] * shape;
    c.remainder_cost_N = Polynomial(remainder_cost);
  }

  // C_Y,j Y + C_tau,j (p_k - remainder bound).
  void addConstantForce(const Segment& s, int j, ConstraintPolynomial& c) const {
    const Eigen::MatrixXd& Ctau = flat_.Ctau();
    const Eigen::MatrixXd& CY = flat_.CY();
    for (int l = 0; l < p_; ++l) {
      const auto& out = setup_.outputs[static_cast<std::size_t>(l)];
      c.base += CY(j, l) * s.P * out.particular;
      c.G.middleCols(out.offset, out.nullspace.cols()) += CY(j, l) * s.P * out.nullspace;
    }
    double remainder_weight = 0.0;
    for (int i = 0; i < n_; ++i) {
      const Eigen::VectorXd tc = s.piece->torque[static_cast<std::size_t>(i)].composeAffine(s.a, s.b).coefficients();
      c.base.head(tc.size()) += Ctau(j, i) * tc;
      remainder_weight += std::abs(Ctau(j, i)) * s.piece->remainder_N_m[i];
    }
    c.remainder_cost_N = Polynomial(remainder_weight * s.remainder_shape.coefficients());
    c.base.head(s.remainder_shape.coefficients().size()) -= c.remainder_cost_N.coefficients();
  }

  ConstraintPolynomial flatOutputConstraint(const Segment& s, int l) const {
    const auto& out = setup_.outputs[static_cast<std::size_t>(l)];
    ConstraintPolynomial c;
    c.flat_output = l;
    c.name = "flat output '" + flat_.flatOutputs().names[static_cast<std::size_t>(l)] + "' >= 0";
    c.base = s.P * out.particular;
    c.G = Eigen::MatrixXd::Zero(D_ + 1, n_theta_);
    c.G.middleCols(out.offset, out.nullspace.cols()) = s.P * out.nullspace;
    return c;
  }

  // One pricing of the forces: weights w, their split at q = 0 (constant moment arms), and the
  // cost vector and constant it adds to.
  struct CostWeights {
    const Eigen::VectorXd weights_w;
    const EffortSplit constant_split;
    Eigen::VectorXd& cost;
    double& constant;
  };

  EffortSplit splitOf(const Eigen::VectorXd& weights_w) const {
    if (varying_ || flat_.effortIsFlatOutputSum()) return {};
    return {flat_.CY().transpose() * weights_w, flat_.Ctau().transpose() * weights_w};
  }

  // The integral of w^T F = w^T C_tau tau + sum_l (C_Y^T w)_l Y_l over the segment. The paper's
  // weights (E^T 1) give exactly sum_l Y_l. Others: constants with constant moment arms; with
  // posture-dependent ones this piece's modelled base force and coupling polynomials (each within
  // its remainder bound of the exact C(q(t))^-1).
  void addCost(const Segment& s, const CostWeights& w) {
    const bool flat_output_sum = flat_.effortIsFlatOutputSum();
    for (int l = 0; l < p_; ++l) {
      const Eigen::RowVectorXd weights = (s.t1 - s.t0) * flatOutputCostRow(s, l, w) * s.P;
      const auto& out = setup_.outputs[static_cast<std::size_t>(l)];
      w.constant += weights.dot(out.particular);
      if (out.nullspace.cols()) w.cost.segment(out.offset, out.nullspace.cols()) += (weights * out.nullspace).transpose();
    }
    if (flat_output_sum) return;
    const double piece_length = s.piece->t1_s - s.piece->t0_s;
    for (int i = 0; i < (varying_ ? m_ : n_); ++i) {
      const double weight = varying_ ? w.weights_w[i] : w.constant_split.torques[i];
      const Polynomial& signal =
          varying_ ? s.piece->base_force[static_cast<std::size_t>(i)] : s.piece->torque[static_cast<std::size_t>(i)];
      w.constant += weight * piece_length * signal.integral(s.a, s.a + s.b);
    }
  }

  // Flat output l's cost weight over the segment as a row on powers of s (integrals over [0, 1]).
  Eigen::RowVectorXd flatOutputCostRow(const Segment& s, int l, const CostWeights& w) const {
    if (flat_.effortIsFlatOutputSum()) return mean_weights_.transpose();
    if (!varying_) return w.constant_split.flat_outputs[l] * mean_weights_.transpose();
    Eigen::VectorXd c_l = Eigen::VectorXd::Zero(1);
    for (int j = 0; j < m_; ++j) {
      const Eigen::VectorXd cj =
          w.weights_w[j] * s.piece->coupling[static_cast<std::size_t>(j * p_ + l)].composeAffine(s.a, s.b).coefficients();
      if (cj.size() > c_l.size()) c_l.conservativeResizeLike(Eigen::VectorXd::Zero(cj.size()));
      c_l.head(cj.size()) += cj;
    }
    Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(D_ + 1);  // integral over [0, 1] of c_l(s) s^k
    for (int power = 0; power <= D_; ++power)
      for (Eigen::Index i = 0; i < c_l.size(); ++i) row[power] += c_l[i] / static_cast<double>(i + power + 1);
    return row;
  }

  const FlatOutputMap& flat_;
  const TorqueModel& torque_;
  const FlatOutputBoundary& bc_;
  const Eigen::VectorXd& reserves_;
  const SosSettings& o_;
  const int m_, n_, p_, d_;
  const bool varying_;
  SosSetup setup_;
  int n_theta_ = 0, D_ = 0;
  Eigen::VectorXd mean_weights_;
};

}  // namespace

SosSetup set_up_sos_program(const FlatOutputMap& flat, const TorqueModel& torque, double T, const FlatOutputBoundary& bc,
                            const Eigen::VectorXd& reserves, const SosSettings& o) {
  require_valid_inputs(flat, torque, T, bc, reserves, o);
  return SetupBuilder(flat, torque, T, bc, reserves, o).build();
}

}  // namespace flatsos::planner::detail
