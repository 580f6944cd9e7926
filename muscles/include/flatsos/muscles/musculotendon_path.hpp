#pragma once
// A muscle's path over a model's joints: its musculotendon length L(q) is a LengthPolynomial
// whose arguments are some of the model's joint coordinates and, for coordinates the model does
// not have, values held fixed. Moment arms are the negative gradient, r_i(q) = -dL/dq_i, so the
// muscle's tendon force F gives the joint torques tau_i = r_i(q) F and dL/dt = -r(q)^T qd.
// Constant moment arms are the order-1 case: L = l0 - sum_i d_i q_i. Every quantity along a
// joint motion is exact (partial derivatives as polynomials, Taylor arithmetic in time).
// Pure math: no Eigen, no Simbody. Vectors over the model's joints have numJoints() entries.

#include <vector>

#include "flatsos/muscles/length_polynomial.hpp"

namespace flatsos::muscles {

/// One argument of the length polynomial: a model joint (its index in q) or a held value.
struct PathCoordinate {
  int joint = -1;               ///< index into the model's q; -1: held at held_value_rad
  double held_value_rad = 0.0;  ///< used when joint < 0
  bool held() const { return joint < 0; }
};

class MusculotendonPath {
 public:
  /// No joints, length 0.
  MusculotendonPath() = default;
  /// Throws std::invalid_argument for coordinates.size() != length_m.dimension(), a joint index
  /// outside [0, num_joints), a joint given twice, or a held value that is not finite.
  MusculotendonPath(LengthPolynomial length_m, std::vector<PathCoordinate> coordinates, int num_joints);
  /// L = l0 - sum_i d_i q_i over every joint (d has one entry per joint): an order-1 polynomial
  /// of the joints with d_i != 0.
  static MusculotendonPath constantMomentArms(double length_at_zero_angles_m, const std::vector<double>& moment_arms_m);

  int numJoints() const { return num_joints_; }
  const LengthPolynomial& lengthPolynomial() const { return length_; }
  const std::vector<PathCoordinate>& coordinates() const { return coordinates_; }
  /// The joints whose angle changes the length, ascending.
  const std::vector<int>& crossedJoints() const { return crossed_; }
  /// True when every moment arm is the same in every posture (order <= 1).
  bool hasConstantMomentArms() const { return length_.order() <= 1; }

  double length(const double* q_rad) const;
  /// r_i(q) into r_m (numJoints entries; 0 for joints not crossed).
  void momentArms(const double* q_rad, double* r_m) const;
  /// dr_i/dq_k = -d2L/(dq_i dq_k) into out (numJoints x numJoints, row-major, symmetric).
  void momentArmJacobian(const double* q_rad, double* out) const;
  /// d^j L/dt^j, j = 0 .. count - 1 (count <= LengthPolynomial::kMaxJetCount), along a joint
  /// motion with q_jet[j * numJoints() + i] = d^j q_i / dt^j.
  void lengthJet(const double* q_jet, int count, double* out) const;
  /// d^j r_i/dt^j into out[j * numJoints() + i], the same way.
  void momentArmJets(const double* q_jet, int count, double* out) const;

 private:
  // Writes the free arguments (or their jets) from the joints'.
  void arguments(const double* q_jet, int count, double* x_jet) const;

  LengthPolynomial length_;                 ///< as given, over every coordinate
  std::vector<PathCoordinate> coordinates_;
  // What is evaluated: the length with the held coordinates substituted, a polynomial of the
  // free ones only (a knee path fitted over hip, knee and ankle is then one of the knee: 6 terms
  // instead of 56), and its derivatives.
  LengthPolynomial free_length_;
  std::vector<int> free_joint_;             ///< joint of each free argument
  std::vector<LengthPolynomial> gradient_;  ///< d/dx_k per free argument
  std::vector<LengthPolynomial> hessian_;   ///< d2/(dx_k dx_l), row-major over free arguments
  std::vector<int> crossed_;
  int num_joints_ = 0;
};

}  // namespace flatsos::muscles
