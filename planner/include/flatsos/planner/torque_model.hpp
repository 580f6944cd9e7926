#pragma once
// Torque models for the SOS program: tau(t) is not polynomial, so on each of K pieces of the
// horizon it is replaced by a polynomial of degree r plus a bound on the remainder,
//   |tau_i(t) - p_ki(t)| <= e_ki  on piece k.
// K = 1, r = 0 is the paper's single box [tau_min, tau_max] (p = midpoint, e = half range).
// For r >= 1, p interpolates tau at r + 1 Chebyshev points of the piece. The remainder is the
// largest deviation over `samples_per_piece` uniform samples (ends included), inflated by
// `remainder_inflation`: a sampled estimate, made safe by the inflation and checked a
// posteriori by the planner on a dense grid. The conservativeness vanishes as K and r grow.
// The first piece (r >= 2) starts where the initial state fixes tau and dtau/dt exactly: there
// p matches both and interpolates at r - 1 Chebyshev points, and the remainder bound is
// e s^2, zero at t = 0. A constant bound there would demand slack at t = 0 that no plan can
// create: from a rest state whose tendon force equals its reserve, no plan would be feasible.
// With posture-dependent moment arms the tendon forces are F = C_tau(q) tau + C_Y(q) Y with
// coefficients that follow the path: each piece then also models, the same way, each muscle's
// torque part b_j(t) = (C_tau(q(t)) tau(t))_j and each coupling c_jl(t) = C_Y(q(t))_jl.
// docs/method/sos_program.md, "Torque model".

#include <vector>

#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/joint_paths.hpp"
#include "flatsos/planner/numerics/polynomial.hpp"

namespace flatsos::planner {

/// The pieces (torque_model_study.hpp holds their degree and sampling).
struct TorqueModelOptions {
  int pieces = 12;                  ///< K
  /// Each piece this many times as long as the one before (1: uniform). Above 1 the short
  /// pieces follow a fast start, where uniform cubic pieces leave large remainders.
  double piece_growth = 1.0;
};

struct TorquePiece {
  double t0_s = 0.0, t1_s = 0.0;
  std::vector<Polynomial> torque;   ///< per joint, in the piece's scaled time s in [0, 1]
  Eigen::VectorXd remainder_N_m;    ///< e_ki per joint
  /// The bound is |tau_i - p_ki| <= e_ki s^remainder_order: 0 (a constant bound) or 2 (the
  /// first piece, which matches the initial tau and dtau/dt).
  int remainder_order = 0;
  /// e_ki s^order for joint i at scaled time s in [0, 1].
  double remainderAt(int joint, double s) const;

  /// Posture-dependent moment arms only (empty otherwise), with the same remainder order:
  /// |b_j - base_force_j| <= base_force_remainder_N_j s^order and
  /// |c_jl - coupling_{j p + l}| <= coupling_remainder_{j p + l} s^order.
  std::vector<Polynomial> base_force;      ///< per muscle (N)
  Eigen::VectorXd base_force_remainder_N;
  std::vector<Polynomial> coupling;        ///< per muscle j and flat output l at j p + l (dimensionless)
  Eigen::VectorXd coupling_remainder;
};

struct TorqueModel {
  std::vector<TorquePiece> pieces;
  int torque_evaluations = 0;
};

/// Cubic pieces (r = 3) fitted on 16 samples each, remainders inflated by 1.25. Throws
/// std::invalid_argument for K < 1 or a piece growth that is not finite and > 0.
TorqueModel build_torque_model(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const JointPath& path,
                               const TorqueModelOptions& options);

}  // namespace flatsos::planner
