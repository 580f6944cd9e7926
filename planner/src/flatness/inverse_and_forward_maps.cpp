// The flat-output map's inverse (flat outputs -> muscle states and excitations) and forward map
// (muscle state -> flat outputs), at one time (flat_outputs.hpp).
#include "flatsos/planner/flat_outputs.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/muscles/muscle_inverse.hpp"

namespace flatsos::planner {

namespace fm = flatsos::muscles;

MusclePoint FlatOutputMap::inverse(plugin::ModelWorkspace& ws, const Jet& q_jet, const Jet& Y_jet) const {
  return inverseFromTorque(q_jet, torqueJet(ws, q_jet), Y_jet);
}

MusclePoint FlatOutputMap::inverse(const Jet& q_jet, const Jet& Y_jet) const {
  plugin::ModelWorkspace ws = makeWorkspace();
  return inverse(ws, q_jet, Y_jet);
}

MusclePoint FlatOutputMap::inverseFromTorque(const Jet& q_jet, const TorqueJet& tj, const Jet& Y_jet) const {
  MusclePoint p;
  inverseFromTorque(q_jet, tj, Y_jet, p);
  return p;
}

void FlatOutputMap::inverseFromTorque(const Jet& q_jet, const TorqueJet& tj, const Jet& Y_jet, MusclePoint& p) const {
  using Kind = DomainViolation::Kind;
  const int m = numMuscles();
  if (Y_jet.rows() != numFlatOutputs() || Y_jet.cols() < 2)
    throw std::invalid_argument("flat-output jet must be p x (2..3): Y, dY[, ddY]");
  if (q_jet.rows() != numJoints() || q_jet.cols() < 1)
    throw std::invalid_argument("joint jet must be N x (1..5): q[, qd, qdd, ...]");
  if (tj.tau.rows() != numJoints() || tj.tau.cols() != 3)
    throw std::invalid_argument("torque jet must be N x 3: tau, dtau, ddtau");
  const bool has_ddY = Y_jet.cols() > 2;
  // Posture-dependent moment arms: the force jet through C(q) and its rates (allocates).
  const Eigen::MatrixXd varying_F = constant_ ? Eigen::MatrixXd() : forceJet(q_jet, tj.tau, Y_jet);
  for (auto* v : {&p.tendon_force_N, &p.tendon_force_rate_N_per_s, &p.tendon_length_m, &p.tendon_length_rate_m_per_s,
                  &p.fiber_length_m, &p.shortening_velocity_m_per_s, &p.force_ratio, &p.activation,
                  &p.activation_rate_per_s, &p.excitation})
    v->setConstant(m, std::nan(""));  // reuses the storage when the size is unchanged
  p.domain_violation.resize(static_cast<std::size_t>(m));

  for (int j = 0; j < m; ++j) {
    const fm::MuscleParameters& mp = model_->muscle(j).getParameters();
    DomainViolation& why = p.domain_violation[static_cast<std::size_t>(j)];
    why = DomainViolation{};
    // F = C_tau tau + C_Y Y and its two time derivatives; L(q) and its derivatives along the path.
    const double F = constant_ ? Ctau_.row(j).dot(tj.tau.col(0)) + CY_.row(j).dot(Y_jet.col(0)) : varying_F(j, 0);
    const double dF = constant_ ? Ctau_.row(j).dot(tj.tau.col(1)) + CY_.row(j).dot(Y_jet.col(1)) : varying_F(j, 1);
    const double ddF = constant_ ? Ctau_.row(j).dot(tj.tau.col(2)) + (has_ddY ? CY_.row(j).dot(Y_jet.col(2)) : 0.0)
                                 : varying_F(j, 2);
    const fm::SecondOrderJet path = pathLengthJet(j, q_jet);
    p.tendon_force_N[j] = F;
    p.tendon_force_rate_N_per_s[j] = dF;
    const fm::MuscleInverse inv = fm::invert_muscle(mp, {F, dF, ddF}, path, false);
    if (inv.stage == fm::MuscleInverse::Stage::SlackTendon) {
      why = {Kind::SlackTendon, F, 0.0};
      continue;
    }
    p.tendon_length_m[j] = inv.tendon_length_m;
    p.tendon_length_rate_m_per_s[j] = inv.tendon_length_rate_m_per_s;
    if (inv.stage == fm::MuscleInverse::Stage::FiberCollapsed) {
      why = {Kind::FiberCollapsed, inv.fiber_length_m, 0.0};
      continue;
    }
    p.fiber_length_m[j] = inv.fiber_length_m;
    p.shortening_velocity_m_per_s[j] = inv.shortening_velocity_m_per_s;
    p.force_ratio[j] = inv.force_ratio;
    if (inv.stage == fm::MuscleInverse::Stage::NoForceCapacity) {
      why = {Kind::NoForceCapacity, inv.shortening_velocity_m_per_s, mp.max_shortening_velocity_m_per_s()};
      continue;
    }
    const double g = inv.force_ratio, a = inv.activation, da = inv.activation_rate_per_s;
    p.activation[j] = a;
    p.activation_rate_per_s[j] = da;
    p.excitation[j] = inv.excitation;
    if (g > fm::force_ratio_exact_upper_bound(mp))
      why = {Kind::ForceRatioBeyondExactRange, g, fm::force_ratio_exact_upper_bound(mp)};
    else if (!(a > 0.0 && a <= 1.0))
      why = {Kind::ActivationOutsideUnitInterval, a, 1.0};
    else if (a < mp.activation_floor)
      why = {Kind::ActivationBelowFloor, a, mp.activation_floor};
    else if (!inv.excitation_real)
      why = {Kind::ExcitationUnattainable, da, 0.0};
    else if (!(inv.excitation >= mp.model->minimumExcitation(mp) && inv.excitation <= 1.0))
      why = {Kind::ExcitationOutsideUnitInterval, inv.excitation, 1.0};
  }
}

muscles::SecondOrderJet FlatOutputMap::pathLengthJet(int j, const Jet& q_jet) const {
  // Constant moment arms: dL/dt = -A^T qd, d2L/dt2 = -A^T qdd.
  if (constant_)
    return {model_->musculotendonLength(j, q_jet.col(0)), q_jet.cols() > 1 ? -A_.col(j).dot(q_jet.col(1)) : 0.0,
            q_jet.cols() > 2 ? -A_.col(j).dot(q_jet.col(2)) : 0.0};
  const int n = numJoints();
  Eigen::MatrixXd jet = Eigen::MatrixXd::Zero(n, 3);
  const Eigen::Index given = std::min<Eigen::Index>(3, q_jet.cols());
  jet.leftCols(given) = q_jet.leftCols(given);
  double L[3];
  model_->musclePath(j).lengthJet(jet.data(), 3, L);
  return {L[0], L[1], L[2]};
}

void FlatOutputMap::pathLengthJetGradient(int j, const Jet& q_jet, Eigen::Ref<Eigen::MatrixXd> out) const {
  if (out.rows() != 3 || out.cols() != 5 * q_jet.rows())
    throw std::invalid_argument("path-length jet gradient: the output must be 3 x 5N");
  requireConstant(A_, "the path-length jet gradient");
  // Constant moment arms: d^k L / dt^k = -A^T q^(k) (k >= 1) and L = L(q): order k of L moves
  // only with order k of q.
  out.setZero();
  for (int r = 0; r < q_jet.rows(); ++r)
    for (int k = 0; k < 3; ++k) out(k, 5 * r + k) = -A_(r, j);
}

FlatState FlatOutputMap::forward(const MuscleState& s) const {
  plugin::ModelWorkspace ws = makeWorkspace();
  return forward(ws, s);
}

FlatState FlatOutputMap::forward(plugin::ModelWorkspace& ws, const MuscleState& s) const {
  const int n = numJoints(), m = numMuscles();
  auto check = [](const Eigen::VectorXd& v, int size, const char* what) {
    if (v.size() != size || !v.allFinite())
      throw std::invalid_argument(std::string("muscle state: ") + what + " must have " + std::to_string(size) +
                                  " finite values");
  };
  check(s.q_rad, n, "q");
  check(s.qd_rad_per_s, n, "qd");
  check(s.tendon_length_m, m, "tendon lengths");
  check(s.activation, m, "activations");
  Eigen::VectorXd F(m), dF(m);
  const Eigen::VectorXd L = model_->musculotendonLengths(s.q_rad);
  // R(q) and dR/dt = sum_k dR/dq_k qd_k (posture-dependent paths) or A and 0.
  Eigen::MatrixXd R = momentArms(s.q_rad), dR = Eigen::MatrixXd::Zero(n, m);
  if (!constant_) {
    Eigen::MatrixXd jet(n, 2), arm_jet(n, 2);
    jet << s.q_rad, s.qd_rad_per_s;
    for (int j = 0; j < m; ++j) {
      model_->musclePath(j).momentArmJets(jet.data(), 2, arm_jet.data());
      dR.col(j) = arm_jet.col(1);
    }
  }
  const Eigen::VectorXd dL = -R.transpose() * s.qd_rad_per_s;
  for (int j = 0; j < m; ++j) {
    const fm::MuscleParameters& mp = model_->muscle(j).getParameters();
    F[j] = fm::tendon_force(mp, s.tendon_length_m[j]);
    const double dls = fm::tendon_length_derivative(mp, s.tendon_length_m[j], s.activation[j], L[j], dL[j]);
    dF[j] = fm::tendon_force_derivative(mp, s.tendon_length_m[j]) * dls;
  }
  const Eigen::VectorXd tau = R * F, dtau = R * dF + dR * F;
  const Eigen::MatrixXd M = model_->massMatrix(ws, s.q_rad);
  const Eigen::LDLT<Eigen::MatrixXd> Minv(M);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  const Eigen::VectorXd qdd = Minv.solve(tau - torque(ws, s.q_rad, s.qd_rad_per_s, zero));
  // dtau = d/dt ID(q, qd, qdd) = [terms with q''' = 0] + M q'''.
  Jet jet = Eigen::MatrixXd::Zero(n, 4);
  jet.col(0) = s.q_rad;
  jet.col(1) = s.qd_rad_per_s;
  jet.col(2) = qdd;
  const Eigen::VectorXd dtau0 = torqueJet(ws, jet).tau.col(1);
  FlatState out;
  out.q = jet;
  out.q.col(3) = Minv.solve(dtau - dtau0);
  out.Y.resize(numFlatOutputs(), 2);
  out.Y.col(0) = E_ * F;
  out.Y.col(1) = E_ * dF;
  return out;
}

}  // namespace flatsos::planner
