#include "flatsos/planner/torque_model.hpp"

#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>

namespace flatsos::planner {

double TorquePiece::remainderAt(int joint, double s) const {
  return remainder_N_m[joint] * std::pow(s, remainder_order);
}

TorqueModel build_torque_model(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const JointPath& path,
                               const TorqueModelOptions& o) {
  if (o.pieces < 1) throw std::invalid_argument("torque model: pieces K must be >= 1");
  if (o.degree < 0) throw std::invalid_argument("torque model: degree r must be >= 0");
  if (o.samples_per_piece < 2 || o.samples_per_piece < o.degree + 1)
    throw std::invalid_argument("torque model: need at least max(2, r + 1) samples per piece");
  if (!(o.remainder_inflation >= 1.0)) throw std::invalid_argument("torque model: remainder inflation must be >= 1");
  const int n = flat.numJoints();
  const double T = path.duration_s;
  auto tau_at = [&](double t) {
    const Jet j = path.jet(t, 3);
    return flat.torque(workspace, j.col(0), j.col(1), j.col(2));
  };
  // tau and dtau/dt at t = 0 (fixed by the initial state) for the first piece's Hermite model.
  const bool hermite_start = o.degree >= 2;
  const Eigen::MatrixXd tau_start = hermite_start ? flat.torqueJet(workspace, path.jet(0.0, 5)).tau : Eigen::MatrixXd();

  TorqueModel model;
  for (int k = 0; k < o.pieces; ++k) {
    TorquePiece piece;
    piece.t0_s = T * k / o.pieces;
    piece.t1_s = T * (k + 1) / o.pieces;
    const double h = piece.t1_s - piece.t0_s;
    const int ns = o.samples_per_piece;
    Eigen::VectorXd s_samples(ns);
    Eigen::MatrixXd tau_samples(n, ns);
    for (int i = 0; i < ns; ++i) {
      s_samples[i] = static_cast<double>(i) / (ns - 1);
      tau_samples.col(i) = tau_at(piece.t0_s + h * s_samples[i]);
    }
    model.torque_evaluations += ns;
    piece.remainder_N_m.resize(n);
    const bool hermite = hermite_start && k == 0;
    const Eigen::VectorXd nodes = chebyshev_nodes_unit_interval(o.degree + 1);
    Eigen::MatrixXd node_torques(n, nodes.size());
    if (o.degree > 0) {
      for (int c = 0; c < nodes.size(); ++c) node_torques.col(c) = tau_at(piece.t0_s + h * nodes[c]);
      model.torque_evaluations += static_cast<int>(nodes.size());
    }
    if (hermite) {
      // p(s) = tau(0) + h tau'(0) s + s^2 g(s), g interpolating (tau - tau(0) - h tau'(0) s) / s^2
      // at the nodes; the bound is on that quotient: |tau - p| / s^2 = |quotient - g|.
      piece.remainder_order = 2;
      auto quotient = [&](int joint, double s, double tau) {
        return (tau - tau_start(joint, 0) - h * tau_start(joint, 1) * s) / (s * s);
      };
      for (int joint = 0; joint < n; ++joint) {
        Eigen::VectorXd values(nodes.size());
        for (int c = 0; c < nodes.size(); ++c) values[c] = quotient(joint, nodes[c], node_torques(joint, c));
        const Polynomial g = interpolating_polynomial(nodes, values);
        Eigen::VectorXd coefficients = Eigen::VectorXd::Zero(g.coefficients().size() + 2);
        coefficients[0] = tau_start(joint, 0);
        coefficients[1] = h * tau_start(joint, 1);
        coefficients.tail(g.coefficients().size()) = g.coefficients();
        // At s = 0 the quotient is its limit h^2 tau''(0) / 2 (the samples start there).
        double dev = std::abs(0.5 * h * h * tau_start(joint, 2) - g(0.0));
        for (int i = 0; i < ns; ++i)
          if (s_samples[i] > 0.0) dev = std::max(dev, std::abs(quotient(joint, s_samples[i], tau_samples(joint, i)) - g(s_samples[i])));
        piece.remainder_N_m[joint] = o.remainder_inflation * dev;
        piece.torque.emplace_back(coefficients);
      }
      model.pieces.push_back(std::move(piece));
      continue;
    }
    for (int joint = 0; joint < n; ++joint) {
      Polynomial p;
      if (o.degree == 0) {
        const double lo = tau_samples.row(joint).minCoeff(), hi = tau_samples.row(joint).maxCoeff();
        p = Polynomial(Eigen::VectorXd::Constant(1, 0.5 * (lo + hi)));
      } else {
        p = interpolating_polynomial(nodes, node_torques.row(joint).transpose());
      }
      double dev = 0.0;
      for (int i = 0; i < ns; ++i) dev = std::max(dev, std::abs(tau_samples(joint, i) - p(s_samples[i])));
      piece.remainder_N_m[joint] = o.degree == 0 ? dev : o.remainder_inflation * dev;
      piece.torque.push_back(p);
    }
    model.pieces.push_back(std::move(piece));
  }
  return model;
}

}  // namespace flatsos::planner
