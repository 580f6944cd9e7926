#include "flatsos/planner/muscle_state_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "flatsos/muscles/hill_laws.hpp"

namespace flatsos::planner {

namespace fm = flatsos::muscles;

namespace {
constexpr double kGamma = 1.0 + 0.70710678118654752440;  // ROS2's gamma = 1 + 1/sqrt(2)
constexpr double kSafety = 0.9, kMaxGrowth = 5.0, kMaxShrink = 0.2;
constexpr double kMinStep_s = 1e-10;
constexpr double kFirstStep_s = 1e-3;  // each muscle's first trial step
// A pivot of W = I - gamma h J below this is a step far beyond an unstable time scale of the
// muscle (J > 0 on the descending limb): rejected, as the plant's Rosenbrock integrator does.
constexpr double kMinPivot = 0.5;

double clamped_excitation(const plugin::ExcitationPolynomial& piece, double t) {
  const double n = piece.value(t);
  return std::isnan(n) ? 0.0 : std::clamp(n, 0.0, 1.0);  // as the Simbody muscle reads it
}

// d/dt of the clamped excitation (0 where the piece holds its end or the clamp is active).
double excitation_rate(const plugin::ExcitationPolynomial& piece, double t) {
  const double s = (t - piece.start_time_s) / piece.duration_s;
  if (!(s >= 0.0 && s <= 1.0)) return 0.0;
  const double n = piece.value(t);
  if (!(n > 0.0 && n < 1.0)) return 0.0;
  double slope = 0.0;
  for (int i = piece.count - 1; i >= 1; --i) slope = slope * s + i * piece.coefficients[static_cast<std::size_t>(i)];
  return slope / piece.duration_s;
}
}  // namespace

MuscleStateEstimator::MuscleStateEstimator(std::shared_ptr<const plugin::MusculoskeletalModel> model, double accuracy)
    : model_(std::move(model)), accuracy_(accuracy) {
  if (!model_) throw std::invalid_argument("muscle state estimator: no model");
  if (!(accuracy_ > 0.0 && accuracy_ <= 0.1)) throw std::invalid_argument("muscle state estimator: accuracy must be in (0, 0.1]");
  const int n = model_->numJoints(), m = model_->numMuscles();
  tendon_length_m_.setZero(m);
  activation_.setZero(m);
  excitation_.assign(static_cast<std::size_t>(m), plugin::ExcitationPolynomial::constant(0.0));
  step_s_.assign(static_cast<std::size_t>(m), kFirstStep_s);
  saved_tendon_m_.setZero(m);
  saved_activation_.setZero(m);
  arms_m_.setZero(n);
  quintic_.setZero(n, 6);
  jet_.setZero(3 * n);
}

void MuscleStateEstimator::start(const Eigen::VectorXd& tendon_lengths_m, const Eigen::VectorXd& activations,
                                 double time_s) {
  const int m = model_->numMuscles();
  if (tendon_lengths_m.size() != m || activations.size() != m)
    throw std::invalid_argument("muscle state estimator: need one tendon length and one activation per muscle (" +
                                std::to_string(m) + ")");
  if (!tendon_lengths_m.allFinite() || !activations.allFinite() || !std::isfinite(time_s))
    throw std::invalid_argument("muscle state estimator: the start states and time must be finite");
  tendon_length_m_ = tendon_lengths_m;
  activation_ = activations;
  time_s_ = time_s;
  std::fill(step_s_.begin(), step_s_.end(), kFirstStep_s);
  started_ = true;
}

void MuscleStateEstimator::setExcitation(int muscle, const plugin::ExcitationPolynomial& piece) {
  piece.validate();  // its coefficient count and duration are read unchecked while integrating
  excitation_.at(static_cast<std::size_t>(muscle)) = piece;
}

void MuscleStateEstimator::jointJetAt(double t) {
  const int n = model_->numJoints();
  const double s = (t - advance_start_s_) / advance_duration_s_, T = advance_duration_s_;
  for (int i = 0; i < n; ++i) {
    double q = 0.0, dq = 0.0, ddq = 0.0;  // in s, by Horner
    for (int c = 5; c >= 0; --c) {
      ddq = ddq * s + 2.0 * dq;
      dq = dq * s + q;
      q = q * s + quintic_(i, c);
    }
    jet_[i] = q;
    jet_[n + i] = dq / T;
    jet_[2 * n + i] = ddq / (T * T);
  }
}

void MuscleStateEstimator::rates(int j, double t, double tendon_length_m, double activation, double& d_tendon,
                                 double& d_activation) const {
  const fm::MuscleParameters& p = model_->description().muscles[static_cast<std::size_t>(j)].parameters;
  double length_jet[2];
  model_->musclePath(j).lengthJet(jet_.data(), 2, length_jet);  // reads q and qd of jet_
  d_tendon = fm::tendon_length_derivative(p, tendon_length_m, activation, length_jet[0], length_jet[1]);
  d_activation = fm::activation_derivative(p, clamped_excitation(excitation_[static_cast<std::size_t>(j)], t), activation);
}

bool MuscleStateEstimator::tryStep(int j, double t, double h, double& ls, double& a, double& error_norm) {
  // Non-autonomous ROS2 with W = I - gamma h J, J the partials of (dL_S/dt, da/dt) in (L_S, a)
  // at the step's start (upper triangular: da/dt does not depend on L_S) and f_t their partial
  // in time:  W k1 = f(t, y) + gamma h f_t;  W k2 = f(t + h, y + h k1) - 2 k1 - gamma h f_t;
  // y += h (3/2 k1 + 1/2 k2); the embedded first-order solution is y + h k1.
  const fm::MuscleParameters& p = model_->description().muscles[static_cast<std::size_t>(j)].parameters;
  const plugin::ExcitationPolynomial& piece = excitation_[static_cast<std::size_t>(j)];
  jointJetAt(t);
  double length_jet[3];
  model_->musclePath(j).lengthJet(jet_.data(), 3, length_jet);
  const fm::TendonLengthDerivativePartials dls = fm::tendon_length_derivative_partials(p, ls, a, length_jet[0]);
  const fm::ActivationRate da = p.model->activationRate(p, clamped_excitation(piece, t), a);
  const double w11 = 1.0 - kGamma * h * dls.d_tendon_length_per_s, w22 = 1.0 - kGamma * h * da.d_activation;
  const double w12 = -kGamma * h * dls.d_activation_m_per_s;
  if (!(w11 >= kMinPivot && w22 >= kMinPivot)) return false;
  const auto solve = [&](double r_tendon, double r_activation, double& k_tendon, double& k_activation) {
    k_activation = r_activation / w22;
    k_tendon = (r_tendon - w12 * k_activation) / w11;
  };
  // dL_S/dt depends on time through L and dL/dt (partial 1); da/dt through the excitation.
  const double ft_tendon = kGamma * h * (dls.d_musculotendon_length_per_s * length_jet[1] + length_jet[2]);
  const double ft_activation = kGamma * h * da.d_excitation * excitation_rate(piece, t);
  double f_tendon, f_activation, k1_tendon, k1_activation, k2_tendon, k2_activation;
  rates(j, t, ls, a, f_tendon, f_activation);
  solve(f_tendon + ft_tendon, f_activation + ft_activation, k1_tendon, k1_activation);
  jointJetAt(t + h);
  rates(j, t + h, ls + h * k1_tendon, a + h * k1_activation, f_tendon, f_activation);
  solve(f_tendon - 2.0 * k1_tendon - ft_tendon, f_activation - 2.0 * k1_activation - ft_activation, k2_tendon, k2_activation);
  // The error filtered through W^-1, so a fast mode that the method damps correctly is not
  // counted as error (Shampine's filter, as in the plant's integrator).
  double e_tendon, e_activation;
  solve(0.5 * h * (k1_tendon + k2_tendon), 0.5 * h * (k1_activation + k2_activation), e_tendon, e_activation);
  const double stretch_scale_m = p.tendon_strain_at_max_force * p.tendon_slack_length_m;
  error_norm = std::max(std::abs(e_tendon) / stretch_scale_m, std::abs(e_activation)) / accuracy_;
  ls += h * (1.5 * k1_tendon + 0.5 * k2_tendon);
  a += h * (1.5 * k1_activation + 0.5 * k2_activation);
  return std::isfinite(ls) && std::isfinite(a) && std::isfinite(error_norm);
}

bool MuscleStateEstimator::advanceMuscle(int j, double t_end) {
  double t = time_s_, ls = tendon_length_m_[j], a = activation_[j];
  double& h = step_s_[static_cast<std::size_t>(j)];
  while (t < t_end) {
    const bool last = h >= t_end - t;
    const double step = last ? t_end - t : h;
    double ls_new = ls, a_new = a, error_norm = 0.0;
    const bool ok = tryStep(j, t, step, ls_new, a_new, error_norm);
    const bool accepted = ok && error_norm <= 1.0;
    if (accepted) {
      t = last ? t_end : t + step;
      ls = ls_new, a = a_new;
    }
    const double factor = ok ? kSafety / std::sqrt(std::max(error_norm, 1e-10)) : kMaxShrink;
    const double proposed = step * std::clamp(factor, kMaxShrink, accepted ? kMaxGrowth : 1.0);
    // A last step cut short by the advance's end says little about the step size: keep h then.
    h = accepted && last ? std::max(h, proposed) : proposed;
    if (h < kMinStep_s) return false;
  }
  tendon_length_m_[j] = ls;
  activation_[j] = a;
  return true;
}

bool MuscleStateEstimator::advance(const JointMeasurement& from, const JointMeasurement& to, double time_s) {
  if (!started_) throw std::logic_error("muscle state estimator: advance before start");
  const double T = time_s - time_s_;
  if (!(T >= 0.0) || !std::isfinite(time_s)) throw std::invalid_argument("muscle state estimator: time must not go back");
  for (const JointMeasurement* x : {&from, &to})
    if (!(x->q_rad.allFinite() && x->qd_rad_per_s.allFinite() && x->qdd_rad_per_s2.allFinite())) return false;
  if (T == 0.0) return true;
  // The quintic in s = (t - t0) / T through both ends' q, qd, qdd.
  for (int i = 0; i < model_->numJoints(); ++i) {
    const double P0 = from.q_rad[i], V0 = T * from.qd_rad_per_s[i], A0 = T * T * from.qdd_rad_per_s2[i];
    const double P1 = to.q_rad[i], V1 = T * to.qd_rad_per_s[i], A1 = T * T * to.qdd_rad_per_s2[i];
    quintic_(i, 0) = P0;
    quintic_(i, 1) = V0;
    quintic_(i, 2) = 0.5 * A0;
    quintic_(i, 3) = -10.0 * P0 - 6.0 * V0 - 1.5 * A0 + 10.0 * P1 - 4.0 * V1 + 0.5 * A1;
    quintic_(i, 4) = 15.0 * P0 + 8.0 * V0 + 1.5 * A0 - 15.0 * P1 + 7.0 * V1 - A1;
    quintic_(i, 5) = -6.0 * P0 - 3.0 * V0 - 0.5 * A0 + 6.0 * P1 - 3.0 * V1 + 0.5 * A1;
  }
  advance_start_s_ = time_s_;
  advance_duration_s_ = T;
  // When one muscle's integration fails, every muscle keeps its states and the time stays.
  saved_tendon_m_ = tendon_length_m_;  // same sizes every advance: no allocation
  saved_activation_ = activation_;
  for (int j = 0; j < model_->numMuscles(); ++j) {
    if (advanceMuscle(j, time_s)) continue;
    tendon_length_m_ = saved_tendon_m_;
    activation_ = saved_activation_;
    std::fill(step_s_.begin(), step_s_.end(), kFirstStep_s);  // a failed muscle left its step at nothing
    return false;
  }
  time_s_ = time_s;
  return true;
}

void MuscleStateEstimator::muscleTorques(const Eigen::VectorXd& q, Eigen::VectorXd& out) const {
  const int n = model_->numJoints(), m = model_->numMuscles();
  out.setZero(n);
  for (int j = 0; j < m; ++j) {
    const fm::MuscleParameters& p = model_->description().muscles[static_cast<std::size_t>(j)].parameters;
    const double force = fm::tendon_force(p, tendon_length_m_[j]);
    model_->musclePath(j).momentArms(q.data(), arms_m_.data());
    out.noalias() += force * arms_m_;
  }
}

}  // namespace flatsos::planner
