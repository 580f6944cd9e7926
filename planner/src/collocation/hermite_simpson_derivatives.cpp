// The Hermite-Simpson transcription's Jacobian and Hessian of the Lagrangian (their sparsity is
// fixed when the problem is built, hence the constructor here).
#include "collocation/hermite_simpson.hpp"
#include "collocation/hermite_simpson_terms.hpp"

#include <memory>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "flatsos/muscles/hill_laws.hpp"

namespace flatsos::planner::detail {

template <class Sink>
void HermiteSimpsonProblem::visitJacobian(const double* x, Sink&& sink) const {
  const int P = points(), m = muscles(), N = joints();
  const Eigen::MatrixXd& A = samples_.moment_arms_m;
  for (int i = 0; i < P; ++i)
    for (int j = 0; j < m; ++j) {
      const MuscleAt e = evaluate(x, i, j);
      const int row = equilibriumRow(i, j);
      sink(row, index(i, j, kStretch), e.F_s / muscles_[j].parameters.max_isometric_force_N - e.a * e.f_s * e.g);
      sink(row, index(i, j, kActivation), -e.f * e.g);
      sink(row, index(i, j, kVelocity), -e.a * e.f * e.g_v);
      if (free_)  // d(-a f g)/dq_r = -a g f_L dL/dq_r, dL/dq_r = -A_rj
        for (int r = 0; r < N; ++r)
          if (A(r, j) != 0.0) sink(row, jointIndex(i, r, kAngle), e.a * e.g * e.f_L * A(r, j));
    }
  Eigen::MatrixXd torque_jacobian;  // d tau / d(q, qd, qdd) at a point, free path
  for (int i = firstTorquePoint(); i < P; ++i) {
    if (free_)
      free_->dynamics->inverseDynamicsJacobian(jointVector(x, i, kAngle), jointVector(x, i, kSpeed),
                                               jointVector(x, i, kAcceleration), torque_jacobian);
    const Eigen::MatrixXd& arms = armsAt(i);
    for (int r = 0; r < N; ++r) {
      for (int j = 0; j < m; ++j)
        if (arms(r, j) != 0.0)
          sink(torqueRow(i, r), index(i, j, kStretch),
               arms(r, j) * muscles::tendon_force_derivative(muscles_[j].parameters, tendonLength(x, i, j)) *
                   stretch_scale_m_[j]);
      if (free_)
        for (int c = 0; c < 3 * N; ++c)
          sink(torqueRow(i, r), jointIndex(i, c % N, static_cast<JointUnknown>(c / N)), -torque_jacobian(r, c));
    }
  }
  for (int k = 0; k < intervals(); ++k) {
    const double h = intervalLength(k);
    for (int j = 0; j < m; ++j) {
      const auto& p = muscles_[j].parameters;
      const double rate_s_v = p.max_shortening_velocity_m_per_s() / stretch_scale_m_[j];
      // Stretch defects: linear in s and v.
      for (int which = 0; which < 2; ++which) {
        const auto& state = which == 0 ? kSimpsonState : kInterpolationState;
        const auto& rate = which == 0 ? kSimpsonRate : kInterpolationRate;
        for (int c = 0; c < 3; ++c) {
          const int i = 2 * k + c;
          if (state[c] != 0.0) sink(defectRow(k, j, which), index(i, j, kStretch), state[c]);
          if (rate[c] != 0.0) sink(defectRow(k, j, which), index(i, j, kVelocity), h * rate[c] * rate_s_v);
          if (free_ && rate[c] != 0.0)  // dL/dt = -A_j^T qd
            for (int r = 0; r < N; ++r)
              if (A(r, j) != 0.0)
                sink(defectRow(k, j, which), jointIndex(i, r, kSpeed), -h * rate[c] * A(r, j) / stretch_scale_m_[j]);
        }
      }
      // Activation defects: the state's own coefficient and the rate's partials share an entry.
      for (int which = 0; which < 2; ++which) {
        const auto& state = which == 0 ? kSimpsonState : kInterpolationState;
        const auto& rate = which == 0 ? kSimpsonRate : kInterpolationRate;
        for (int c = 0; c < 3; ++c) {
          const int i = 2 * k + c;
          const muscles::ActivationRate fa =
              activation_rate(p, x[index(i, j, kExcitation)], x[index(i, j, kActivation)]);
          if (state[c] != 0.0 || rate[c] != 0.0)
            sink(defectRow(k, j, 2 + which), index(i, j, kActivation), state[c] + h * rate[c] * fa.d_activation);
          if (rate[c] != 0.0) sink(defectRow(k, j, 2 + which), index(i, j, kExcitation), h * rate[c] * fa.d_excitation);
        }
      }
    }
  }
  if (free_)
    for (int k = 0; k < intervals(); ++k)
      for (int r = 0; r < N; ++r)
        for (int which = 0; which < 4; ++which)
          visitJointDefect(k, r, which,
                           [&](int column, double coefficient) { sink(jointDefectRow(k, r, which), column, coefficient); });
  for (int j = 0; j < m; ++j) {
    sink(restRow(j), index(P - 1, j, kActivation), -1.0);
    sink(restRow(j), index(P - 1, j, kExcitation), 1.0);
  }
}

void HermiteSimpsonProblem::jacobianValues(const double* x, double* values) const {
  int k = 0;
  visitJacobian(x, [&](int, int, double v) { values[k++] = v; });
}

template <class Sink>
void HermiteSimpsonProblem::visitHessian(const double* x, double sigma, const double* lambda, Sink&& sink) const {
  const int P = points(), m = muscles(), N = joints();
  const Eigen::MatrixXd& A = samples_.moment_arms_m;
  Eigen::MatrixXd joint_block;  // free path: the point's 3N x 3N joint block, stacked by kind
  for (int i = 0; i < P; ++i) {
    if (free_) joint_block = Eigen::MatrixXd::Zero(3 * N, 3 * N);
    for (int j = 0; j < m; ++j) {
      const auto& p = muscles_[j].parameters;
      const MuscleAt e = evaluate(x, i, j);
      // Second derivative of everything that depends on F(s): cost and torques.
      const MuscleEffortJet term = effortTerm(x, i, j, e.F);
      const double cost_weight = sigma * quadratureWeight(i);
      double F_weight = cost_weight * term.d_force;
      if (i >= firstTorquePoint())
        for (int r = 0; r < N; ++r) F_weight += lambda[torqueRow(i, r)] * armsAt(i)(r, j);
      // The equilibrium row's F / Fmax - a f g.
      const double le = lambda[equilibriumRow(i, j)];
      const double ss = F_weight * e.F_ss + cost_weight * term.d_force2 * e.F_s * e.F_s +
                        le * (e.F_ss / p.max_isometric_force_N - e.a * e.f_ss * e.g);
      const double as = le * (-e.f_s * e.g), vs = le * (-e.a * e.f_s * e.g_v);
      const double va = le * (-e.f * e.g_v), vv = le * (-e.a * e.f * e.g_vv);
      // Activation defects: the weight of f_a(n, a) at this point in each defect row.
      double fa_weight = 0.0;
      if (i % 2 == 1) {
        const int k = i / 2;
        fa_weight = intervalLength(k) * (lambda[defectRow(k, j, 2)] * kSimpsonRate[1] + lambda[defectRow(k, j, 3)] * kInterpolationRate[1]);
      } else {
        if (i < P - 1)  // first point of interval i / 2
          fa_weight += intervalLength(i / 2) * (lambda[defectRow(i / 2, j, 2)] * kSimpsonRate[0] +
                                   lambda[defectRow(i / 2, j, 3)] * kInterpolationRate[0]);
        if (i > 0)  // last point of interval i / 2 - 1
          fa_weight += intervalLength(i / 2 - 1) * (lambda[defectRow(i / 2 - 1, j, 2)] * kSimpsonRate[2] +
                                   lambda[defectRow(i / 2 - 1, j, 3)] * kInterpolationRate[2]);
      }
      const muscles::ActivationRate fa = activation_rate(p, e.n, e.a);
      sink(index(i, j, kStretch), index(i, j, kStretch), ss);
      sink(index(i, j, kActivation), index(i, j, kStretch), as);
      sink(index(i, j, kVelocity), index(i, j, kStretch), vs);
      sink(index(i, j, kVelocity), index(i, j, kActivation), va);
      sink(index(i, j, kVelocity), index(i, j, kVelocity), vv);
      sink(index(i, j, kExcitation), index(i, j, kExcitation),
           fa_weight * fa.d_excitation2 + cost_weight * term.d_excitation2);
      sink(index(i, j, kExcitation), index(i, j, kActivation), fa_weight * fa.d_excitation_activation);
      sink(index(i, j, kActivation), index(i, j, kActivation),
           fa_weight * fa.d_activation2 + cost_weight * term.d_activation2);
      if (free_)  // -a f(L(q) - L_S(s)) g(v) with dL/dq_r = -A_rj, dL_S/ds = lambda_s
        for (int r = 0; r < N; ++r) {
          if (A(r, j) == 0.0) continue;
          sink(jointIndex(i, r, kAngle), index(i, j, kStretch), -le * e.a * e.g * e.f_LL * A(r, j) * stretch_scale_m_[j]);
          sink(jointIndex(i, r, kAngle), index(i, j, kActivation), le * e.g * e.f_L * A(r, j));
          sink(jointIndex(i, r, kAngle), index(i, j, kVelocity), le * e.a * e.g_v * e.f_L * A(r, j));
          for (int r2 = 0; r2 < N; ++r2) joint_block(r, r2) -= le * e.a * e.g * e.f_LL * A(r, j) * A(r2, j);
        }
    }
    if (!free_) continue;
    // The torque rows -tau(q, qd, qdd): minus inverse dynamics' Hessian weighted by their multipliers.
    Eigen::VectorXd torque_multipliers(N);
    for (int r = 0; r < N; ++r) torque_multipliers[r] = lambda[torqueRow(i, r)];
    joint_block -= free_->dynamics->inverseDynamicsHessian(jointVector(x, i, kAngle), jointVector(x, i, kSpeed),
                                                           jointVector(x, i, kAcceleration), torque_multipliers);
    for (int a = 0; a < 3 * N; ++a)
      for (int b = 0; b <= a; ++b) {
        if (a >= 2 * N && b >= N) continue;  // tau is linear in qdd
        sink(jointIndex(i, a % N, static_cast<JointUnknown>(a / N)), jointIndex(i, b % N, static_cast<JointUnknown>(b / N)),
             joint_block(a, b));
      }
  }
}

void HermiteSimpsonProblem::hessianValues(const double* x, double sigma, const double* lambda, double* values) const {
  int k = 0;
  visitHessian(x, sigma, lambda, [&](int, int, double v) { values[k++] = v; });
}

HermiteSimpsonProblem::HermiteSimpsonProblem(std::vector<CollocationMuscle> muscles, PathSamples samples,
                                             std::shared_ptr<const Effort> effort, std::optional<FreeJoints> free,
                                             bool free_muscle_ends)
    : muscles_(std::move(muscles)), samples_(std::move(samples)), effort_(std::move(effort)), free_(std::move(free)),
      free_muscle_ends_(free_muscle_ends) {
  const int P = points(), m = this->muscles(), N = joints();
  if (!effort_) throw std::invalid_argument("Hermite-Simpson: no effort to minimize");
  effort_->validate(m);
  if (P < 3 || P % 2 == 0) throw std::invalid_argument("Hermite-Simpson: need 2K + 1 >= 3 points");
  if (samples_.musculotendon_length_m.rows() != m || samples_.musculotendon_length_m.cols() != P ||
      samples_.lengthening_rate_m_per_s.rows() != m || samples_.lengthening_rate_m_per_s.cols() != P ||
      samples_.torque_N_m.cols() != P || samples_.moment_arms_m.rows() != N || samples_.moment_arms_m.cols() != m)
    throw std::invalid_argument("Hermite-Simpson: path samples of inconsistent sizes");
  if (!samples_.moment_arms_at.empty() && (free_ || static_cast<int>(samples_.moment_arms_at.size()) != P))
    throw std::invalid_argument("Hermite-Simpson: posture-dependent moment arms need a prescribed path and one per point");
  if (samples_.q_rad.rows() != N || samples_.q_rad.cols() != P || samples_.qd_rad_per_s.rows() != N ||
      samples_.qd_rad_per_s.cols() != P || samples_.qdd_rad_per_s2.rows() != N || samples_.qdd_rad_per_s2.cols() != P)
    throw std::invalid_argument("Hermite-Simpson: joint path samples of inconsistent sizes");
  if (free_ && (!free_->dynamics || free_->dynamics->numJoints() != N || free_->length_at_zero_angles_m.size() != m ||
                free_->start_q_rad.size() != N || free_->start_qd_rad_per_s.size() != N || free_->end_q_rad.size() != N))
    throw std::invalid_argument("Hermite-Simpson: free joints of inconsistent sizes");
  for (const auto& mu : muscles_)
    stretch_scale_m_.push_back(mu.parameters.tendon_strain_at_max_force * mu.parameters.tendon_slack_length_m);
  // The structure, recorded once at the start (any point gives the same pattern).
  std::vector<double> x(variables());
  startingPoint(x.data());
  visitJacobian(x.data(), [this](int r, int c, double) { jac_rows_.push_back(r), jac_cols_.push_back(c); });
  std::vector<double> lambda(constraints(), 0.0);
  visitHessian(x.data(), 1.0, lambda.data(),
               [this](int r, int c, double) { hess_rows_.push_back(r), hess_cols_.push_back(c); });
}

}  // namespace flatsos::planner::detail
