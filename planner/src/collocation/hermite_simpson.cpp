#include "collocation/hermite_simpson.hpp"
#include "collocation/hermite_simpson_terms.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <Eigen/Dense>

#include "flatsos/muscles/hill_laws.hpp"

namespace flatsos::planner::detail {

int HermiteSimpsonProblem::constraints() const { return restRow(0) + muscles(); }

double HermiteSimpsonProblem::quadratureWeight(int i) const {
  if (i % 2 == 1) return 4.0 * intervalLength(i / 2) / 6.0;
  double w = 0.0;
  if (i > 0) w += intervalLength(i / 2 - 1) / 6.0;  // the end of the interval before
  if (i < points() - 1) w += intervalLength(i / 2) / 6.0;
  return w;
}

HermiteSimpsonProblem::MuscleAt HermiteSimpsonProblem::evaluate(const double* x, int i, int j) const {
  const auto& p = muscles_[j].parameters;
  const double lambda = stretch_scale_m_[j], vmax = p.max_shortening_velocity_m_per_s();
  MuscleAt e{};
  e.s = x[index(i, j, kStretch)];
  e.a = x[index(i, j, kActivation)];
  e.n = x[index(i, j, kExcitation)];
  e.v = x[index(i, j, kVelocity)];
  const double tendon_length = p.tendon_slack_length_m + lambda * e.s;
  // One evaluation of each law gives its value and both derivatives.
  const muscles::CurveJet tendon = p.model->tendonForce(p, tendon_length);
  e.F = tendon.value;
  e.F_s = tendon.slope * lambda;
  e.F_ss = tendon.curvature * lambda * lambda;
  const double fiber_length = musculotendonLength(x, i, j) - tendon_length;
  const muscles::CurveJet fl = p.model->activeForceLength(p, fiber_length);
  e.f = fl.value;
  e.f_s = -fl.slope * lambda;
  e.f_L = fl.slope;
  e.f_LL = fl.curvature;
  e.f_ss = e.f_LL * lambda * lambda;
  const muscles::CurveJet fv = p.model->forceVelocity(p, vmax * e.v);
  e.g = fv.value;
  e.g_v = fv.slope * vmax;
  e.g_vv = fv.curvature * vmax * vmax;
  return e;
}

double HermiteSimpsonProblem::tendonForce(const double* x, int i, int j) const {
  return muscles::tendon_force(muscles_[j].parameters, tendonLength(x, i, j));
}
double HermiteSimpsonProblem::stretchAtForce(int j, double force_N) const {
  const muscles::MuscleParameters& p = muscles_[j].parameters;
  if (!(force_N > 0.0)) return 0.0;  // a slack tendon: no force at any stretch <= 0
  return (muscles::tendon_length_from_force(p, force_N) - p.tendon_slack_length_m) / stretch_scale_m_[j];
}
double HermiteSimpsonProblem::tendonLength(const double* x, int i, int j) const {
  return muscles_[j].parameters.tendon_slack_length_m + stretch_scale_m_[j] * x[index(i, j, kStretch)];
}
double HermiteSimpsonProblem::shorteningVelocity(const double* x, int i, int j) const {
  return muscles_[j].parameters.max_shortening_velocity_m_per_s() * x[index(i, j, kVelocity)];
}
double HermiteSimpsonProblem::activationRate(const double* x, int i, int j) const {
  return activation_rate(muscles_[j].parameters, x[index(i, j, kExcitation)], x[index(i, j, kActivation)]).value;
}
double HermiteSimpsonProblem::joint(const double* x, int i, int r, JointUnknown k) const {
  if (free_) return x[jointIndex(i, r, k)];
  const Eigen::MatrixXd& path = k == kAngle ? samples_.q_rad : k == kSpeed ? samples_.qd_rad_per_s : samples_.qdd_rad_per_s2;
  return path(r, i);
}
Eigen::VectorXd HermiteSimpsonProblem::jointVector(const double* x, int i, JointUnknown k) const {
  Eigen::VectorXd v(joints());
  for (int r = 0; r < joints(); ++r) v[r] = joint(x, i, r, k);
  return v;
}
double HermiteSimpsonProblem::musculotendonLength(const double* x, int i, int j) const {
  if (!free_) return samples_.musculotendon_length_m(j, i);
  return free_->length_at_zero_angles_m[j] - samples_.moment_arms_m.col(j).dot(jointVector(x, i, kAngle));
}
double HermiteSimpsonProblem::lengtheningRate(const double* x, int i, int j) const {
  if (!free_) return samples_.lengthening_rate_m_per_s(j, i);
  return -samples_.moment_arms_m.col(j).dot(jointVector(x, i, kSpeed));
}
Eigen::VectorXd HermiteSimpsonProblem::torque(const double* x, int i) const {
  if (!free_) return samples_.torque_N_m.col(i);
  plugin::PinTreeDynamics::Scratch scratch = free_->dynamics->makeScratch();
  Eigen::VectorXd tau(joints());
  free_->dynamics->inverseDynamics(scratch, jointVector(x, i, kAngle), jointVector(x, i, kSpeed),
                                   jointVector(x, i, kAcceleration), tau);
  return tau;
}

void HermiteSimpsonProblem::bounds(double* xl, double* xu, double* gl, double* gu) const {
  const int P = points(), m = muscles();
  for (int i = 0; i < P; ++i)
    for (int j = 0; j < m; ++j) {
      const auto& mu = muscles_[j];
      const auto& p = mu.parameters;
      // The tendon force grows with the stretch: the reserve is a bound on s.
      xl[index(i, j, kStretch)] = stretchAtForce(j, mu.reserve_N);
      xu[index(i, j, kStretch)] = kInfinity;
      xl[index(i, j, kActivation)] = mu.min_activation;
      xu[index(i, j, kActivation)] = 1.0;
      xl[index(i, j, kExcitation)] = p.model->minimumExcitation(p);
      xu[index(i, j, kExcitation)] = 1.0;
      // Beyond Vmax the fibre has no force (g <= 0). Lengthening is limited to where the
      // force-velocity law is exact in the forward model (z <= z_hi; beyond, the simulator
      // continues g^-1 linearly to avoid its pole at gmax, and the flatness planner reports a
      // plan that needs it as outside the valid domain).
      xl[index(i, j, kVelocity)] =
          muscles::force_velocity_inverse(p, muscles::force_ratio_exact_upper_bound(p)) / p.max_shortening_velocity_m_per_s();
      xu[index(i, j, kVelocity)] = 1.0;
      if (i == 0 && !free_muscle_ends_) {  // the initial state
        xl[index(i, j, kStretch)] = xu[index(i, j, kStretch)] = mu.initial_stretch;
        xl[index(i, j, kActivation)] = xu[index(i, j, kActivation)] = mu.initial_activation;
      }
      if (i == P - 1 && !free_muscle_ends_) {  // rest at T: dL_S/dt = u + dL/dt = 0 (a free path ends with qd = 0)
        xl[index(i, j, kVelocity)] = xu[index(i, j, kVelocity)] =
            free_ ? 0.0 : -samples_.lengthening_rate_m_per_s(j, i) / p.max_shortening_velocity_m_per_s();
      }
    }
  if (free_)
    for (int i = 0; i < P; ++i)
      for (int r = 0; r < joints(); ++r)
        for (JointUnknown k : {kAngle, kSpeed, kAcceleration}) {
          double lower = -kInfinity, upper = kInfinity;
          if (i == 0 && k == kAngle) lower = upper = free_->start_q_rad[r];
          if (i == 0 && k == kSpeed) lower = upper = free_->start_qd_rad_per_s[r];
          if (i == P - 1) lower = upper = k == kAngle ? free_->end_q_rad[r] : 0.0;
          xl[jointIndex(i, r, k)] = lower, xu[jointIndex(i, r, k)] = upper;
        }
  std::fill(gl, gl + constraints(), 0.0);
  std::fill(gu, gu + constraints(), 0.0);
  if (free_muscle_ends_)
    for (int j = 0; j < m; ++j) gl[restRow(j)] = -kInfinity, gu[restRow(j)] = kInfinity;
}

void HermiteSimpsonProblem::startingPoint(double* x) const {
  const int P = points(), m = muscles();
  Eigen::VectorXd fmax(m);
  for (int j = 0; j < m; ++j) fmax[j] = muscles_[j].parameters.max_isometric_force_N;
  const Eigen::MatrixXd W = fmax.array().square().matrix().asDiagonal();
  for (int i = 0; i < P; ++i) {
    // min sum (F_j / Fmax_j)^2 subject to A F = tau.
    const Eigen::MatrixXd& A = armsAt(i);
    const Eigen::VectorXd F = W * A.transpose() * (A * W * A.transpose()).ldlt().solve(samples_.torque_N_m.col(i));
    for (int j = 0; j < m; ++j) {
      const auto& mu = muscles_[j];
      const auto& p = mu.parameters;
      double s, a;
      if (i == 0 && !free_muscle_ends_) {
        s = mu.initial_stretch, a = mu.initial_activation;
      } else {
        const double force = std::max(F[j], mu.reserve_N + 0.01 * p.max_isometric_force_N);
        s = stretchAtForce(j, force);
        const double fiber_length = samples_.musculotendon_length_m(j, i) - p.tendon_slack_length_m - stretch_scale_m_[j] * s;
        a = std::clamp(force / (p.max_isometric_force_N * muscles::force_length(p, fiber_length)),
                       std::max(mu.min_activation, 1e-3), 1.0);
      }
      x[index(i, j, kStretch)] = s;
      x[index(i, j, kActivation)] = a;
      x[index(i, j, kExcitation)] = a;
      x[index(i, j, kVelocity)] = 0.0;
    }
  }
  // The start's fibre velocity at t = 0 from the initial state's equilibrium; rest at T.
  for (int j = 0; j < m; ++j) {
    const auto& p = muscles_[j].parameters;
    const double tendon_length = tendonLength(x, 0, j);
    const double u = muscles::fiber_shortening_velocity(p, muscles::tendon_force(p, tendon_length), x[index(0, j, kActivation)],
                                                        samples_.musculotendon_length_m(j, 0) - tendon_length);
    x[index(0, j, kVelocity)] = std::min(u / p.max_shortening_velocity_m_per_s(), 0.99);
    x[index(P - 1, j, kVelocity)] =
        free_ ? 0.0 : -samples_.lengthening_rate_m_per_s(j, P - 1) / p.max_shortening_velocity_m_per_s();
  }
  if (free_)  // the sampled path, its ends replaced by the problem's
    for (int i = 0; i < P; ++i)
      for (int r = 0; r < joints(); ++r) {
        x[jointIndex(i, r, kAngle)] = samples_.q_rad(r, i);
        x[jointIndex(i, r, kSpeed)] = samples_.qd_rad_per_s(r, i);
        x[jointIndex(i, r, kAcceleration)] = samples_.qdd_rad_per_s2(r, i);
      }
  if (free_)
    for (int r = 0; r < joints(); ++r) {
      x[jointIndex(0, r, kAngle)] = free_->start_q_rad[r];
      x[jointIndex(0, r, kSpeed)] = free_->start_qd_rad_per_s[r];
      x[jointIndex(P - 1, r, kAngle)] = free_->end_q_rad[r];
      x[jointIndex(P - 1, r, kSpeed)] = x[jointIndex(P - 1, r, kAcceleration)] = 0.0;
    }
}

MuscleEffortJet HermiteSimpsonProblem::effortTerm(const double* x, int i, int j, double tendon_force_N) const {
  return effort_->muscleTerm(j, muscles_[j].parameters, tendon_force_N, x[index(i, j, kActivation)],
                             x[index(i, j, kExcitation)]);
}

double HermiteSimpsonProblem::objective(const double* x) const {
  double sum = 0.0;
  for (int i = 0; i < points(); ++i)
    for (int j = 0; j < muscles(); ++j) sum += quadratureWeight(i) * effortTerm(x, i, j, tendonForce(x, i, j)).value;
  return sum;
}

void HermiteSimpsonProblem::objectiveGradient(const double* x, double* grad) const {
  std::fill(grad, grad + variables(), 0.0);
  for (int i = 0; i < points(); ++i)
    for (int j = 0; j < muscles(); ++j) {
      const auto& p = muscles_[j].parameters;
      const muscles::CurveJet tendon = p.model->tendonForce(p, tendonLength(x, i, j));
      const MuscleEffortJet term = effortTerm(x, i, j, tendon.value);
      const double w = quadratureWeight(i);
      grad[index(i, j, kStretch)] = w * term.d_force * tendon.slope * stretch_scale_m_[j];
      grad[index(i, j, kActivation)] = w * term.d_activation;
      grad[index(i, j, kExcitation)] = w * term.d_excitation;
    }
}

void HermiteSimpsonProblem::constraintValues(const double* x, double* g) const {
  const int P = points(), m = muscles(), N = joints();
  Eigen::VectorXd F(m);
  for (int i = 0; i < P; ++i) {
    const Eigen::MatrixXd& A = armsAt(i);
    for (int j = 0; j < m; ++j) {
      const MuscleAt e = evaluate(x, i, j);
      F[j] = e.F;
      g[equilibriumRow(i, j)] = e.F / muscles_[j].parameters.max_isometric_force_N - e.a * e.f * e.g;
    }
    if (i >= firstTorquePoint()) {
      const Eigen::VectorXd tau = torque(x, i);
      for (int r = 0; r < N; ++r) g[torqueRow(i, r)] = A.row(r).dot(F) - tau[r];
    }
  }
  for (int k = 0; k < intervals(); ++k) {
    const double h = intervalLength(k);
    for (int j = 0; j < m; ++j) {
      const auto& p = muscles_[j].parameters;
      const double vmax = p.max_shortening_velocity_m_per_s();
      double sim_s = 0.0, int_s = 0.0, sim_a = 0.0, int_a = 0.0;
      for (int c = 0; c < 3; ++c) {
        const int i = 2 * k + c;
        const double s = x[index(i, j, kStretch)], a = x[index(i, j, kActivation)];
        const double rate_s = (vmax * x[index(i, j, kVelocity)] + lengtheningRate(x, i, j)) / stretch_scale_m_[j];
        const double rate_a = activation_rate(p, x[index(i, j, kExcitation)], a).value;
        sim_s += kSimpsonState[c] * s + h * kSimpsonRate[c] * rate_s;
        int_s += kInterpolationState[c] * s + h * kInterpolationRate[c] * rate_s;
        sim_a += kSimpsonState[c] * a + h * kSimpsonRate[c] * rate_a;
        int_a += kInterpolationState[c] * a + h * kInterpolationRate[c] * rate_a;
      }
      g[defectRow(k, j, 0)] = sim_s;
      g[defectRow(k, j, 1)] = int_s;
      g[defectRow(k, j, 2)] = sim_a;
      g[defectRow(k, j, 3)] = int_a;
    }
  }
  if (free_)
    for (int k = 0; k < intervals(); ++k)
      for (int r = 0; r < N; ++r)
        for (int which = 0; which < 4; ++which) {
          double defect = 0.0;
          visitJointDefect(k, r, which, [&](int column, double coefficient) { defect += coefficient * x[column]; });
          g[jointDefectRow(k, r, which)] = defect;
        }
  for (int j = 0; j < m; ++j)
    g[restRow(j)] = x[index(P - 1, j, kExcitation)] - x[index(P - 1, j, kActivation)];
}

}  // namespace flatsos::planner::detail
