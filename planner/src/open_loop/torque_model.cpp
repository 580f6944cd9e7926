#include "flatsos/planner/torque_model.hpp"
#include "flatsos/planner/torque_model_study.hpp"

#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>

#include "flatsos/planner/numerics/bspline.hpp"

namespace flatsos::planner {

double TorquePiece::remainderAt(int joint, double s) const {
  return remainder_N_m[joint] * std::pow(s, remainder_order);
}

namespace {

// One vector signal on one piece: its values at the uniform samples and at the Chebyshev nodes
// (one row per component), and, on the first piece with r >= 2, its value and first two time
// derivatives at t = 0 (rows x 3).
struct PieceSamples {
  Eigen::VectorXd s;        // scaled sample times in [0, 1], ends included
  Eigen::MatrixXd samples;  // rows x s.size()
  Eigen::VectorXd nodes;    // scaled node times
  Eigen::MatrixXd at_nodes; // rows x nodes.size() (r >= 1)
  const Eigen::MatrixXd* start = nullptr;  // Hermite start, or null
};

struct PieceFit {
  std::vector<Polynomial> polynomials;
  Eigen::VectorXd remainder;
};

// Polynomial + remainder per component (the header's rules): r = 0 the box of the samples, r >= 1
// interpolation at the nodes with the inflated sampled deviation; the Hermite start matches value
// and rate at s = 0 and bounds the deviation by e s^2.
PieceFit fit_piece(const PieceSamples& in, double h, int degree, double inflation) {
  const Eigen::Index rows = in.samples.rows(), ns = in.s.size();
  PieceFit fit;
  fit.remainder.resize(rows);
  for (Eigen::Index c = 0; c < rows; ++c) {
    if (in.start) {
      // p(s) = x(0) + h x'(0) s + s^2 g(s), g interpolating (x - x(0) - h x'(0) s) / s^2 at the
      // nodes; the bound is on that quotient: |x - p| / s^2 = |quotient - g|.
      const Eigen::MatrixXd& x0 = *in.start;
      auto quotient = [&](double s, double x) { return (x - x0(c, 0) - h * x0(c, 1) * s) / (s * s); };
      Eigen::VectorXd values(in.nodes.size());
      for (Eigen::Index k = 0; k < in.nodes.size(); ++k) values[k] = quotient(in.nodes[k], in.at_nodes(c, k));
      const Polynomial g = interpolating_polynomial(in.nodes, values);
      Eigen::VectorXd coefficients = Eigen::VectorXd::Zero(g.coefficients().size() + 2);
      coefficients[0] = x0(c, 0);
      coefficients[1] = h * x0(c, 1);
      coefficients.tail(g.coefficients().size()) = g.coefficients();
      // At s = 0 the quotient is its limit h^2 x''(0) / 2 (the samples start there).
      double dev = std::abs(0.5 * h * h * x0(c, 2) - g(0.0));
      for (Eigen::Index i = 0; i < ns; ++i)
        if (in.s[i] > 0.0) dev = std::max(dev, std::abs(quotient(in.s[i], in.samples(c, i)) - g(in.s[i])));
      fit.remainder[c] = inflation * dev;
      fit.polynomials.emplace_back(coefficients);
      continue;
    }
    Polynomial p;
    if (degree == 0) {
      const double lo = in.samples.row(c).minCoeff(), hi = in.samples.row(c).maxCoeff();
      p = Polynomial(Eigen::VectorXd::Constant(1, 0.5 * (lo + hi)));
    } else {
      p = interpolating_polynomial(in.nodes, in.at_nodes.row(c).transpose());
    }
    double dev = 0.0;
    for (Eigen::Index i = 0; i < ns; ++i) dev = std::max(dev, std::abs(in.samples(c, i) - p(in.s[i])));
    fit.remainder[c] = degree == 0 ? dev : inflation * dev;
    fit.polynomials.push_back(p);
  }
  return fit;
}

// The posture-dependent coefficients at one time as one signal: b = C_tau(q) tau (m), then
// C_Y(q) row by row (m p).
Eigen::VectorXd coupling_signal(const FlatOutputMap& flat, const Jet& q_jet, const Eigen::VectorXd& tau) {
  const ForceJetMap map = flat.forceJetMap(q_jet);
  const int m = flat.numMuscles(), p = flat.numFlatOutputs();
  Eigen::VectorXd out(m + m * p);
  out.head(m) = map.Ctau * tau;
  for (int j = 0; j < m; ++j) out.segment(m + j * p, p) = map.CY.row(j).transpose();
  return out;
}

// Its value and first two time derivatives at a point of the motion (rows x 3), from the torque
// jet: b's jet is the force jet with Y = 0, C_Y's is (C_Y, W10 C_Y, W20 C_Y) (flat_outputs.hpp).
Eigen::MatrixXd coupling_jet(const FlatOutputMap& flat, const Jet& q_jet, const Eigen::MatrixXd& tau_jet) {
  const ForceJetMap map = flat.forceJetMap(q_jet);
  const int m = flat.numMuscles(), p = flat.numFlatOutputs();
  Eigen::MatrixXd out(m + m * p, 3);
  out.topRows(m) = map.forceJet(tau_jet, Eigen::MatrixXd::Zero(p, 2));
  Eigen::MatrixXd v0 = map.CY, v1 = Eigen::MatrixXd::Zero(m, p), v2 = Eigen::MatrixXd::Zero(m, p);
  map.mix(v0, v1, v2);
  const std::array<const Eigen::MatrixXd*, 3> orders = {&v0, &v1, &v2};
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < m; ++j) out.col(k).segment(m + j * p, p) = orders[static_cast<std::size_t>(k)]->row(j).transpose();
  return out;
}

// The pieces and their study settings in one place.
struct TorqueModelSettings : TorqueModelOptions, TorqueModelStudyOptions {
  TorqueModelSettings(const TorqueModelOptions& options, const TorqueModelStudyOptions& study)
      : TorqueModelOptions(options), TorqueModelStudyOptions(study) {}
};

}  // namespace

TorqueModel build_torque_model(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const JointPath& path,
                               const TorqueModelOptions& options) {
  return build_torque_model(flat, workspace, path, options, TorqueModelStudyOptions{});
}

TorqueModel build_torque_model(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const JointPath& path,
                               const TorqueModelOptions& options, const TorqueModelStudyOptions& study) {
  const TorqueModelSettings o(options, study);
  if (o.pieces < 1) throw std::invalid_argument("torque model: pieces K must be >= 1");
  if (o.degree < 0) throw std::invalid_argument("torque model: degree r must be >= 0");
  if (o.samples_per_piece < 2 || o.samples_per_piece < o.degree + 1)
    throw std::invalid_argument("torque model: need at least max(2, r + 1) samples per piece");
  if (!(o.remainder_inflation >= 1.0)) throw std::invalid_argument("torque model: remainder inflation must be >= 1");
  if (!(o.piece_growth > 0.0) || !std::isfinite(o.piece_growth))
    throw std::invalid_argument("torque model: piece_growth must be finite and > 0 (1: uniform pieces)");
  const int n = flat.numJoints(), m = flat.numMuscles(), p = flat.numFlatOutputs();
  const bool varying = !flat.hasConstantMomentArms();
  const int coupled = varying ? m + m * p : 0;
  const double T = path.duration_s;
  // tau at t, and with posture-dependent arms the coupling signal too (one inverse dynamics).
  auto sample = [&](double t, Eigen::Ref<Eigen::VectorXd> tau, Eigen::Ref<Eigen::VectorXd> coupling) {
    const Jet j = path.jet(t, 3);
    tau = flat.torque(workspace, j.col(0), j.col(1), j.col(2));
    if (varying) coupling = coupling_signal(flat, j, tau);
  };
  // tau and dtau/dt at t = 0 (fixed by the initial state) for the first piece's Hermite model.
  const bool hermite_start = o.degree >= 2;
  Eigen::MatrixXd tau_start, coupling_start;
  if (hermite_start) {
    const Jet j0 = path.jet(0.0, 5);
    tau_start = flat.torqueJet(workspace, j0).tau;
    if (varying) coupling_start = coupling_jet(flat, j0, tau_start);
  }

  TorqueModel model;
  const Eigen::VectorXd nodes = chebyshev_nodes_unit_interval(o.degree + 1);
  const std::vector<double> breaks = geometric_breakpoints(o.pieces, T, o.piece_growth);
  for (int k = 0; k < o.pieces; ++k) {
    TorquePiece piece;
    piece.t0_s = breaks[k];
    piece.t1_s = breaks[k + 1];
    const double h = piece.t1_s - piece.t0_s;
    const int ns = o.samples_per_piece;
    PieceSamples torque, coupling;
    torque.s.resize(ns);
    torque.samples.resize(n, ns);
    coupling.samples.resize(coupled, ns);
    for (int i = 0; i < ns; ++i) {
      torque.s[i] = static_cast<double>(i) / (ns - 1);
      sample(piece.t0_s + h * torque.s[i], torque.samples.col(i), coupling.samples.col(i));
    }
    model.torque_evaluations += ns;
    torque.nodes = nodes;
    torque.at_nodes.resize(n, nodes.size());
    coupling.at_nodes.resize(coupled, nodes.size());
    if (o.degree > 0) {
      for (Eigen::Index c = 0; c < nodes.size(); ++c)
        sample(piece.t0_s + h * nodes[c], torque.at_nodes.col(c), coupling.at_nodes.col(c));
      model.torque_evaluations += static_cast<int>(nodes.size());
    }
    coupling.s = torque.s;
    coupling.nodes = nodes;
    const bool hermite = hermite_start && k == 0;
    if (hermite) {
      piece.remainder_order = 2;
      torque.start = &tau_start;
      coupling.start = &coupling_start;
    }
    PieceFit tau_fit = fit_piece(torque, h, o.degree, o.remainder_inflation);
    piece.torque = std::move(tau_fit.polynomials);
    piece.remainder_N_m = tau_fit.remainder;
    if (varying) {
      PieceFit c_fit = fit_piece(coupling, h, o.degree, o.remainder_inflation);
      piece.base_force.assign(c_fit.polynomials.begin(), c_fit.polynomials.begin() + m);
      piece.coupling.assign(c_fit.polynomials.begin() + m, c_fit.polynomials.end());
      piece.base_force_remainder_N = c_fit.remainder.head(m);
      piece.coupling_remainder = c_fit.remainder.tail(m * p);
    }
    model.pieces.push_back(std::move(piece));
  }
  return model;
}

}  // namespace flatsos::planner
