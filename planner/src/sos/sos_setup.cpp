#include "sos/sos_setup.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <Eigen/Dense>

#include "numerics/lukacs_basis.hpp"

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

}  // namespace

Eigen::RowVectorXd monomials(double s, Eigen::Index size) {
  Eigen::RowVectorXd v(size);
  double p = 1.0;
  for (Eigen::Index j = 0; j < size; ++j, p *= s) v[j] = p;
  return v;
}

SosSetup set_up_sos_program(const FlatOutputMap& flat, const TorqueModel& torque, double T, const FlatOutputBoundary& bc,
                            const Eigen::VectorXd& reserves, const SosSettings& o) {
  require_valid_inputs(flat, torque, T, bc, reserves, o);
  const int m = flat.numMuscles(), n = flat.numJoints(), p = flat.numFlatOutputs();
  const int d = o.flat_output_degree;
  SosSetup setup(T, BSplineBasis::geometric(d, o.flat_output_spans, T, o.flat_output_span_growth));
  const BSplineBasis& basis = setup.basis;
  setup.torque = &torque;

  // --- eliminate the boundary equalities ---
  auto& outputs = setup.outputs;
  int n_theta = 0;
  for (int l = 0; l < p; ++l) {
    outputs.push_back(eliminate_equalities(basis, bc, l));
    outputs.back().offset = n_theta;
    n_theta += static_cast<int>(outputs.back().nullspace.cols());
  }

  // --- constraint polynomials per segment, in the segment's scaled time ---
  // With posture-dependent moment arms each tendon force is b_j + sum_l c_jl Y_l with modelled
  // b_j and c_jl; where Y_l >= 0, c_jl Y_l >= (c_jl's polynomial - its remainder bound) Y_l: a
  // polynomial of degree d + r, still affine in theta.
  const bool varying = !flat.hasConstantMomentArms();
  if (varying)
    for (const auto& piece : torque.pieces)
      if (piece.coupling.size() != static_cast<std::size_t>(m * p))
        throw std::invalid_argument("SOS program: the torque model has no coupling model for this model's posture-dependent "
                                    "moment arms (build it with this flat-output map)");
  int r = 2;  // the first piece's remainder bound is quadratic
  for (const auto& piece : torque.pieces) {
    for (const auto& poly : piece.torque) r = std::max(r, poly.degree());
    for (const auto& poly : piece.base_force) r = std::max(r, poly.degree());
  }
  int coupling_degree = 0;
  for (const auto& piece : torque.pieces) {
    if (!varying) break;
    coupling_degree = std::max(coupling_degree, piece.remainder_order);
    for (const auto& poly : piece.coupling) coupling_degree = std::max(coupling_degree, poly.degree());
  }
  const int D = std::max(d + coupling_degree, r);
  auto& constraints = setup.constraints;
  // Y = E F exactly (E C_tau = 0, E C_Y = I), so with E >= 0 entrywise and F >= reserve >= 0
  // the constraints Y >= 0 are implied and left out; the coupling's bound needs them imposed.
  const bool y_implied = !varying && flat.E().minCoeff() >= 0.0;
  const std::vector<double> breaks = segment_breaks(torque, basis);
  Eigen::VectorXd mean_weights(D + 1);  // integral over [0, 1] of s^j
  for (int j = 0; j <= D; ++j) mean_weights[j] = 1.0 / (j + 1);
  LinearProgram& lp = setup.lp;
  lp.cost = Eigen::VectorXd::Zero(n_theta);
  const bool flat_output_sum = flat.effortIsFlatOutputSum();
  const Eigen::VectorXd& weights_w = flat.effortWeights();
  const EffortSplit constant_split =
      varying || flat_output_sum ? EffortSplit{} : flat.effortSplit(Eigen::VectorXd::Zero(n));
  for (std::size_t seg = 0; seg + 1 < breaks.size(); ++seg) {
    const double t0 = breaks[seg], t1 = breaks[seg + 1], mid = 0.5 * (t0 + t1);
    const int k = piece_at(torque, mid);
    const TorquePiece& piece = torque.pieces[static_cast<std::size_t>(k)];
    const int span = basis.spanAt(mid);
    // Both scaled times as affine functions of the segment's s: s_piece = a + b s, s_span = as + bs s.
    const double b = (t1 - t0) / (piece.t1_s - piece.t0_s), a = (t0 - piece.t0_s) / (piece.t1_s - piece.t0_s);
    const double h = basis.spanLength(span);
    const double bs = (t1 - t0) / h, as = (t0 - basis.spanStart(span)) / h;
    // Y's coefficients -> powers of s on this segment.
    Eigen::MatrixXd P = Eigen::MatrixXd::Zero(D + 1, basis.size());
    P.topRows(d + 1) = affine_composition(d + 1, as, bs) * basis.spanPowerMatrix(span);
    // s_piece^order as a polynomial of the segment's s: (a + b s)^order.
    const Polynomial remainder_shape(affine_composition(piece.remainder_order + 1, a, b).col(piece.remainder_order));
    const bool starts_at_zero = seg == 0;
    const int margin_order = starts_at_zero ? piece.remainder_order : 0;
    // At t = 0 the initial state fixes the value; with a constant remainder bound the LP row
    // there carries it, with the vanishing bound (order 2) it is data, checked by fixed_violation.
    std::vector<double> initial_points;  // the exchange adds interior minima where violated
    for (int i = 1; i <= o.exchange.initial_interior_points; ++i) initial_points.push_back(i / (o.exchange.initial_interior_points + 1.0));
    initial_points.push_back(1.0);
    if (starts_at_zero && margin_order == 0) initial_points.insert(initial_points.begin(), 0.0);
    auto add = [&](ConstraintPolynomial c) {
      c.t0_s = t0;
      c.t1_s = t1;
      c.piece = k;
      c.margin_order = margin_order;
      c.points = initial_points;
      c.sticky.assign(initial_points.size(), false);
      constraints.push_back(std::move(c));
    };
    for (int j = 0; j < m; ++j) {
      ConstraintPolynomial c;
      c.muscle = j;
      c.base = Eigen::VectorXd::Zero(D + 1);
      c.G = Eigen::MatrixXd::Zero(D + 1, n_theta);
      if (varying) {
        // sum_l (c_jl - e_jl s^order) Y_l + b_j - e_bj s^order.
        Eigen::VectorXd remainder_cost = piece.base_force_remainder_N[j] * remainder_shape.coefficients();
        remainder_cost.conservativeResize(D + 1);
        remainder_cost.tail(D + 1 - remainder_shape.coefficients().size()).setZero();
        for (int l = 0; l < p; ++l) {
          const auto& out = outputs[static_cast<std::size_t>(l)];
          const std::size_t jl = static_cast<std::size_t>(j * p + l);
          const Polynomial lower = piece.coupling[jl].composeAffine(a, b) - remainder_shape * piece.coupling_remainder[jl];
          const Eigen::MatrixXd times_lower = product_matrix(lower.coefficients(), d + 1, D + 1);
          const Eigen::MatrixXd Yl = P.topRows(d + 1);
          c.base += times_lower * (Yl * out.particular);
          c.G.middleCols(out.offset, out.nullspace.cols()) += times_lower * (Yl * out.nullspace);
          // What the coupling's remainder costs with Y at its particular part (exact when Y is fixed).
          remainder_cost += product_matrix(remainder_shape.coefficients() * piece.coupling_remainder[jl], d + 1, D + 1) *
                            (Yl * out.particular);
        }
        const Eigen::VectorXd bc_poly = piece.base_force[static_cast<std::size_t>(j)].composeAffine(a, b).coefficients();
        c.base.head(bc_poly.size()) += bc_poly;
        c.base.head(remainder_shape.coefficients().size()) -=
            piece.base_force_remainder_N[j] * remainder_shape.coefficients();
        c.remainder_cost_N = Polynomial(remainder_cost);
      } else {
        const Eigen::MatrixXd& Ctau = flat.Ctau();
        const Eigen::MatrixXd& CY = flat.CY();
        for (int l = 0; l < p; ++l) {
          const auto& out = outputs[static_cast<std::size_t>(l)];
          c.base += CY(j, l) * P * out.particular;
          c.G.middleCols(out.offset, out.nullspace.cols()) += CY(j, l) * P * out.nullspace;
        }
        double remainder_weight = 0.0;
        for (int i = 0; i < n; ++i) {
          const Eigen::VectorXd tc = piece.torque[static_cast<std::size_t>(i)].composeAffine(a, b).coefficients();
          c.base.head(tc.size()) += Ctau(j, i) * tc;
          remainder_weight += std::abs(Ctau(j, i)) * piece.remainder_N_m[i];
        }
        c.remainder_cost_N = Polynomial(remainder_weight * remainder_shape.coefficients());
        c.base.head(remainder_shape.coefficients().size()) -= c.remainder_cost_N.coefficients();
      }
      c.base[0] -= reserves[j];
      c.name = "tendon force of muscle '" + flat.model().description().muscles[static_cast<std::size_t>(j)].parameters.name + "'";
      c.reserve_N = reserves[j];
      add(std::move(c));
    }
    for (int l = 0; l < p && !y_implied; ++l) {
      const auto& out = outputs[static_cast<std::size_t>(l)];
      ConstraintPolynomial c;
      c.flat_output = l;
      c.name = "flat output '" + flat.flatOutputs().names[static_cast<std::size_t>(l)] + "' >= 0";
      c.base = P * out.particular;
      c.G = Eigen::MatrixXd::Zero(D + 1, n_theta);
      c.G.middleCols(out.offset, out.nullspace.cols()) = P * out.nullspace;
      add(std::move(c));
    }
    // --- cost: the integral of w^T F = w^T C_tau tau + sum_l (C_Y^T w)_l Y_l over the segment ---
    // The paper's weights (E^T 1) give exactly sum_l Y_l. Others: constants with constant moment
    // arms; with posture-dependent ones this piece's modelled base force and coupling polynomials
    // (each within its remainder bound of the exact C(q(t))^-1).
    const double piece_length = piece.t1_s - piece.t0_s;
    for (int l = 0; l < p; ++l) {
      Eigen::RowVectorXd row;
      if (flat_output_sum) {
        row = mean_weights.transpose();
      } else if (!varying) {
        row = constant_split.flat_outputs[l] * mean_weights.transpose();
      } else {
        Eigen::VectorXd c_l = Eigen::VectorXd::Zero(1);
        for (int j = 0; j < m; ++j) {
          const Eigen::VectorXd cj = weights_w[j] * piece.coupling[static_cast<std::size_t>(j * p + l)].composeAffine(a, b).coefficients();
          if (cj.size() > c_l.size()) c_l.conservativeResizeLike(Eigen::VectorXd::Zero(cj.size()));
          c_l.head(cj.size()) += cj;
        }
        // integral over [0, 1] of c_l(s) s^k
        row = Eigen::RowVectorXd::Zero(D + 1);
        for (int power = 0; power <= D; ++power)
          for (Eigen::Index i = 0; i < c_l.size(); ++i) row[power] += c_l[i] / static_cast<double>(i + power + 1);
      }
      const Eigen::RowVectorXd weights = (t1 - t0) * row * P;
      const auto& out = outputs[static_cast<std::size_t>(l)];
      setup.cost_constant += weights.dot(out.particular);
      if (out.nullspace.cols()) lp.cost.segment(out.offset, out.nullspace.cols()) += (weights * out.nullspace).transpose();
    }
    if (!flat_output_sum)
      for (int i = 0; i < (varying ? m : n); ++i) {
        const double weight = varying ? weights_w[i] : constant_split.torques[i];
        const Polynomial& signal = varying ? piece.base_force[static_cast<std::size_t>(i)] : piece.torque[static_cast<std::size_t>(i)];
        setup.cost_constant += weight * piece_length * signal.integral(a, a + b);
      }
  }
  lp.x_lower = Eigen::VectorXd::Constant(n_theta, -o.exchange.coefficient_bound_N);
  lp.x_upper = Eigen::VectorXd::Constant(n_theta, o.exchange.coefficient_bound_N);
  setup.free_coefficients = n_theta;
  return setup;
}

std::string fixed_violation(const SosSetup& setup, double margin_N) {
  for (const auto& c : setup.constraints) {
    std::vector<double> where = c.points;
    if (c.t0_s == 0.0) where.push_back(0.0);  // t = 0, even where it is no LP point
    for (double s : where) {
      const Eigen::RowVectorXd v = monomials(s, c.base.size());
      const Eigen::RowVectorXd row = v * c.G;
      const double value = v.dot(c.base);
      // Eigen's maxCoeff on an empty vector is undefined: with no free coefficient (the
      // equalities fix Y completely) every row is fixed.
      const double row_size = row.size() ? row.cwiseAbs().maxCoeff() : 0.0;
      const double g_size = c.G.size() ? c.G.cwiseAbs().maxCoeff() : 0.0;
      if (row_size <= 1e-12 * (1.0 + g_size) && value < -margin_N) {
        const double t = c.t0_s + s * (c.t1_s - c.t0_s);
        std::ostringstream why;
        why << "infeasible: at t = " << t << " s the boundary conditions fix Y, and ";
        if (c.muscle >= 0)
          why << "the guaranteed " << c.name << " is " << -value << " N below its reserve of " << c.reserve_N
              << " N (the torque model's remainder bound costs " << c.remainder_cost_N(s)
              << " N there: use more pieces K or a higher degree r)";
        else
          why << c.name << " is violated by " << -value << " N";
        return why.str();
      }
    }
  }
  return "";
}

int build_exchange_rows(SosSetup& setup, double margin_N) {
  std::size_t rows = 0;
  for (const auto& c : setup.constraints) rows += c.points.size();
  LinearProgram& lp = setup.lp;
  lp.G.resize(static_cast<Eigen::Index>(rows), setup.free_coefficients);
  lp.row_lower.resize(static_cast<Eigen::Index>(rows));
  lp.row_upper = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(rows), 1e19);
  Eigen::Index row = 0;
  for (const auto& c : setup.constraints)
    for (double s : c.points) {
      const Eigen::RowVectorXd v = monomials(s, c.base.size());
      lp.G.row(row) = v * c.G;
      double extra = 0.0;
      for (const auto& [at, margin] : c.extra_margin)
        if (at == s) extra += margin;
      lp.row_lower[row] = margin_N * std::pow(s, c.margin_order) + extra - v.dot(c.base);
      ++row;
    }
  return static_cast<int>(rows);
}

bool add_violated_points(SosSetup& setup, const Eigen::VectorXd& theta, double margin_N, double& min_value_N,
                         double tolerance_N, double lift_below_N) {
  bool added = false;
  min_value_N = 1e300;
  // A polynomial on [0, 1] is at least its least Bernstein coefficient. Exact minima (the
  // derivative's roots, by eigenvalues) are found smallest bound first, and no longer once a
  // bound shows no violation and no new least value: the same points and least value for a
  // fraction of the cost where most segments are far from their reserve.
  struct Segment {
    double lower;
    std::size_t index;
    Polynomial p;
  };
  std::vector<Segment> segments;
  segments.reserve(setup.constraints.size());
  for (std::size_t k = 0; k < setup.constraints.size(); ++k) {
    Polynomial p = setup.constraints[k].at(theta);
    // Less the conversion's rounding (sums of the coefficients' size), so that the bound stays one.
    const double lower = from_monomial(GramBasis::Bernstein, p.coefficients()).minCoeff() -
                         1e-13 * (1.0 + p.coefficients().cwiseAbs().sum());
    segments.push_back({std::isnan(lower) ? -std::numeric_limits<double>::infinity() : lower, k, std::move(p)});
  }
  std::sort(segments.begin(), segments.end(), [](const Segment& a, const Segment& b) { return a.lower < b.lower; });
  for (const Segment& segment : segments) {
    if (segment.lower >= min_value_N && segment.lower >= -tolerance_N) break;
    auto& c = setup.constraints[segment.index];
    const IntervalMinimum mn = minimum_on_interval(segment.p, 0.0, 1.0);
    min_value_N = std::min(min_value_N, mn.value);
    if (mn.value < -tolerance_N) {
      const auto known = std::find_if(c.points.begin(), c.points.end(), [&](double s) { return std::abs(s - mn.at) < 1e-9; });
      if (known == c.points.end()) {
        c.points.push_back(mn.at);
        c.sticky.push_back(true);
        if (-mn.value <= lift_below_N) c.extra_margin.emplace_back(mn.at, -mn.value);
      } else {
        // Violated at a point the LP already imposes: it met the row only to its own precision
        // (near t = 0 the margin s^order vanishes, and the bounds' sequential LP holds rows to
        // half the margin). The full margin and twice the violation there, and again if need be.
        c.extra_margin.emplace_back(*known, margin_N - 2.0 * mn.value);
      }
      added = true;
    }
  }
  return added;
}

// Y_l's B-spline coefficients = particular + nullspace theta_l under the boundary equalities.
// The equalities touch only the first and last few coefficients (local support), so the free
// coefficients theta_l are the other B-spline coefficients themselves and the solved-for ones
// depend only on their neighbours: the constraint rows stay sparse and local, and theta is as
// well scaled as the coefficients (newtons). The solved-for columns are chosen by full pivoting.
OutputParameterization eliminate_equalities(const BSplineBasis& basis, const FlatOutputBoundary& bc, int l) {
  const int n_eq = static_cast<int>(bc.initial.cols() + bc.terminal.cols());
  const int size = basis.size();
  Eigen::MatrixXd Aeq(n_eq, size);
  Eigen::VectorXd beq(n_eq);
  int row = 0;
  for (int k = 0; k < bc.initial.cols(); ++k, ++row) {
    Aeq.row(row) = basis.derivativeRow(0.0, k);
    beq[row] = bc.initial(l, k);
  }
  for (int k = 0; k < bc.terminal.cols(); ++k, ++row) {
    Aeq.row(row) = basis.derivativeRow(basis.duration(), bc.terminal_first_order + k);
    beq[row] = bc.terminal(l, k);
  }
  // Each row in units of its largest entry: a derivative of order k scales as 1/h^k, and short
  // spans next to long ones (graded knots) would otherwise fail the rank test on scale alone.
  for (int r = 0; r < n_eq; ++r) {
    const double scale = Aeq.row(r).cwiseAbs().maxCoeff();
    if (scale > 0.0) Aeq.row(r) /= scale, beq[r] /= scale;
  }
  OutputParameterization out;
  out.particular = Eigen::VectorXd::Zero(size);
  if (n_eq == 0) {
    out.nullspace = Eigen::MatrixXd::Identity(size, size);
    return out;
  }
  Eigen::FullPivLU<Eigen::MatrixXd> lu(Aeq);
  lu.setThreshold(1e-10);
  if (lu.rank() < n_eq)
    throw std::invalid_argument("SOS program: the boundary equalities on Y are dependent for this basis");
  std::vector<bool> solved_for(static_cast<std::size_t>(size), false);
  Eigen::MatrixXd A_dep(n_eq, n_eq), A_free(n_eq, size - n_eq);
  std::vector<int> dependent, free;
  for (int i = 0; i < n_eq; ++i) solved_for[static_cast<std::size_t>(lu.permutationQ().indices()[i])] = true;
  for (int j = 0; j < size; ++j) (solved_for[static_cast<std::size_t>(j)] ? dependent : free).push_back(j);
  for (int i = 0; i < n_eq; ++i) A_dep.col(i) = Aeq.col(dependent[static_cast<std::size_t>(i)]);
  for (int i = 0; i < size - n_eq; ++i) A_free.col(i) = Aeq.col(free[static_cast<std::size_t>(i)]);
  const Eigen::PartialPivLU<Eigen::MatrixXd> dep(A_dep);
  const Eigen::VectorXd c_dep = dep.solve(beq);
  out.nullspace = Eigen::MatrixXd::Zero(size, size - n_eq);
  for (int i = 0; i < n_eq; ++i) out.particular[dependent[static_cast<std::size_t>(i)]] = c_dep[i];
  // With no free coefficient (the equalities fix Y) there is no coupling to solve for: Eigen's
  // triangular solve on a matrix without columns binds a reference to null data (UBSan).
  if (size > n_eq) {
    const Eigen::MatrixXd coupling = -dep.solve(A_free);
    for (int i = 0; i < n_eq; ++i) out.nullspace.row(dependent[static_cast<std::size_t>(i)]) = coupling.row(i);
  }
  for (int i = 0; i < size - n_eq; ++i) out.nullspace(free[static_cast<std::size_t>(i)], i) = 1.0;
  return out;
}

SplineTrajectory flat_outputs_of(const SosSetup& setup, const Eigen::VectorXd& theta) {
  Eigen::MatrixXd coefficients(static_cast<Eigen::Index>(setup.outputs.size()), setup.basis.size());
  for (std::size_t l = 0; l < setup.outputs.size(); ++l) {
    const auto& out = setup.outputs[l];
    Eigen::VectorXd c = out.particular;
    if (out.nullspace.cols()) c += out.nullspace * theta.segment(out.offset, out.nullspace.cols());
    coefficients.row(static_cast<Eigen::Index>(l)) = c.transpose();
  }
  return SplineTrajectory(setup.basis, std::move(coefficients));
}

Eigen::VectorXd theta_of(const SosSetup& setup, const SplineTrajectory& Y) {
  if (Y.basis().size() != setup.basis.size() || Y.signals() != static_cast<int>(setup.outputs.size()))
    throw std::logic_error("theta_of: the flat outputs are not in the program's basis");
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(setup.free_coefficients);
  for (std::size_t l = 0; l < setup.outputs.size(); ++l) {
    const auto& out = setup.outputs[l];
    if (!out.nullspace.cols()) continue;
    const Eigen::VectorXd rest = Y.coefficients().row(static_cast<Eigen::Index>(l)).transpose() - out.particular;
    theta.segment(out.offset, out.nullspace.cols()) = out.nullspace.colPivHouseholderQr().solve(rest);
  }
  return theta;
}

}  // namespace flatsos::planner::detail
