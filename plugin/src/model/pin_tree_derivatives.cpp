// The derivatives of the joint tree's inverse dynamics (pin_tree_dynamics.hpp): torque jets along
// a motion, their gradients and Hessians in the jet, and the Jacobian and Hessian in (q, qd, qdd),
// each from the same recursion evaluated in dual numbers (pin_tree_dynamics.cpp instantiates it
// for every scalar type used here).
#include "flatsos/plugin/model/pin_tree_dynamics.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "flatsos/plugin/model/dual_number.hpp"

namespace flatsos::plugin {

namespace {

// The buffers of torque_jet_from_seeds, kept across the passes of one gradient or Hessian.
template <class S>
struct TorqueJetBuffers {
  std::vector<TimeJet<S>> q, qd, qdd, tau;
  PinTreeDynamics::ScratchOf<TimeJet<S>> scratch;
};

// tau along a motion as a time jet: each of q, qd, qdd is (x, x', x'') read from the jet, so tau
// comes out with d/dt and d2/dt2 of tau(t) = ID(q(t), qd(t), qdd(t)). `seed(joint, block)` gives
// that jet for q (block 0), qd (1) or qdd (2) of a joint.
template <class S, class SeedAt>
void torque_jet_from_seeds(const PinTreeDynamics& tree, const SeedAt& seed, std::vector<S>& tau_out,
                           TorqueJetBuffers<S>& buffers) {
  using H = TimeJet<S>;
  const int n = tree.numJoints();
  const auto size = static_cast<std::size_t>(n);
  buffers.q.resize(size), buffers.qd.resize(size), buffers.qdd.resize(size), buffers.tau.resize(size);
  for (int i = 0; i < n; ++i) {
    buffers.q[static_cast<std::size_t>(i)] = seed(i, 0);
    buffers.qd[static_cast<std::size_t>(i)] = seed(i, 1);
    buffers.qdd[static_cast<std::size_t>(i)] = seed(i, 2);
  }
  tree.inverseDynamicsOf<H>(buffers.scratch, buffers.q.data(), buffers.qd.data(), buffers.qdd.data(), buffers.tau.data());
  tau_out.resize(static_cast<std::size_t>(3 * n));
  for (int i = 0; i < n; ++i) {
    const H& t = buffers.tau[static_cast<std::size_t>(i)];
    tau_out[static_cast<std::size_t>(3 * i)] = t.value;
    tau_out[static_cast<std::size_t>(3 * i + 1)] = t.rate;
    tau_out[static_cast<std::size_t>(3 * i + 2)] = t.acceleration;
  }
}

// The same with every seed read from the jet: jet(joint, order), orders 0..4.
template <class S, class JetAt>
void torque_jet_of(const PinTreeDynamics& tree, const JetAt& jet, std::vector<S>& tau_out, TorqueJetBuffers<S>& buffers) {
  torque_jet_from_seeds<S>(
      tree,
      [&](int joint, int block) {
        return TimeJet<S>(jet(joint, block), jet(joint, block + 1), jet(joint, block + 2));
      },
      tau_out, buffers);
}

void require_jet(const PinTreeDynamics& tree, const Eigen::Ref<const Eigen::MatrixXd>& q_jet) {
  if (q_jet.rows() != tree.numJoints() || q_jet.cols() < 5)
    throw std::invalid_argument("torque jet: the joint jet must be " + std::to_string(tree.numJoints()) +
                                " x 5 (q and four derivatives), not " + std::to_string(q_jet.rows()) + " x " +
                                std::to_string(q_jet.cols()));
}

}  // namespace

Eigen::MatrixXd PinTreeDynamics::torqueJet(const Eigen::Ref<const Eigen::MatrixXd>& q_jet) const {
  require_jet(*this, q_jet);
  std::vector<double> tau;
  TorqueJetBuffers<double> buffers;
  torque_jet_of<double>(*this, [&](int r, int l) { return q_jet(r, l); }, tau, buffers);
  Eigen::MatrixXd out(numJoints(), 3);
  for (int i = 0; i < numJoints(); ++i)
    for (int k = 0; k < 3; ++k) out(i, k) = tau[static_cast<std::size_t>(3 * i + k)];
  return out;
}

Eigen::MatrixXd PinTreeDynamics::torqueJet(const Eigen::Ref<const Eigen::MatrixXd>& q_jet,
                                           Eigen::MatrixXd& gradient) const {
  require_jet(*this, q_jet);
  const int n = numJoints();
  gradient.setZero(3 * n, 5 * n);
  Eigen::MatrixXd out(n, 3);
  std::vector<Dual<double>> tau;
  TorqueJetBuffers<Dual<double>> buffers;
  // tau(t) = ID(x(t)) with x = (q, qd, qdd), so d tau^(k) / d x^(j) = binom(k, j) A^(k-j),
  // where A(t) = dID/dx along the motion (the Jacobian of a Taylor expansion is lower
  // block-Toeplitz in the Jacobian's own expansion). One pass per entry of x (3N), with a third
  // infinitesimal constant in time on that entry, gives A e and its first two time derivatives;
  // q^(l) is block l - j of x^(j). One pass per entry of the jet took 5N.
  constexpr double kBinomial[3][3] = {{1.0, 0.0, 0.0}, {1.0, 1.0, 0.0}, {1.0, 2.0, 1.0}};
  using D = Dual<double>;
  for (int r = 0; r < n; ++r)
    for (int b = 0; b < 3; ++b) {
      torque_jet_from_seeds<D>(
          *this,
          [&](int joint, int block) {
            const double x = q_jet(joint, block), x1 = q_jet(joint, block + 1), x2 = q_jet(joint, block + 2);
            return TimeJet<D>(D(x, joint == r && block == b ? 1.0 : 0.0), D(x1), D(x2));
          },
          tau, buffers);
      for (int i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k)
          for (int j = 0; j <= k; ++j)
            gradient(3 * i + k, 5 * r + b + j) +=
                kBinomial[k][j] * tau[static_cast<std::size_t>(3 * i + k - j)].derivative;
    }
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) out(i, k) = tau[static_cast<std::size_t>(3 * i + k)].value;
  return out;
}

Eigen::MatrixXd PinTreeDynamics::torqueJetHessian(const Eigen::Ref<const Eigen::MatrixXd>& q_jet,
                                                  const Eigen::Ref<const Eigen::MatrixXd>& weights) const {
  require_jet(*this, q_jet);
  const int n = numJoints();
  if (weights.rows() != n || weights.cols() != 3)
    throw std::invalid_argument("torque jet Hessian: the weights must be " + std::to_string(n) + " x 3, not " +
                                std::to_string(weights.rows()) + " x " + std::to_string(weights.cols()));
  using S = Dual<Dual<double>>;
  std::vector<S> tau;
  TorqueJetBuffers<S> buffers;
  Eigen::MatrixXd hessian = Eigen::MatrixXd::Zero(5 * n, 5 * n);
  for (int a = 0; a < 5 * n; ++a)
    for (int b = 0; b <= a; ++b) {
      const int la = std::max(a % 5, b % 5), lb = std::min(a % 5, b % 5);
      if ((la == 4 && lb >= 1) || (la == 3 && lb >= 2)) continue;  // structurally zero (above)
      // Entry a carries e3, entry b e4: the e3 e4 coefficient of each tau^(k) is its d2 / da db.
      torque_jet_of<S>(
          *this,
          [&](int joint, int order) {
            const int entry = 5 * joint + order;
            return S(Dual<double>(q_jet(joint, order), entry == b ? 1.0 : 0.0), Dual<double>(entry == a ? 1.0 : 0.0, 0.0));
          },
          tau, buffers);
      double sum = 0.0;
      for (int i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) sum += weights(i, k) * tau[static_cast<std::size_t>(3 * i + k)].derivative.derivative;
      hessian(a, b) = hessian(b, a) = sum;
    }
  return hessian;
}

namespace {
void require_state(const PinTreeDynamics& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                   const Eigen::Ref<const Eigen::VectorXd>& qd, const Eigen::Ref<const Eigen::VectorXd>& qdd) {
  const int n = tree.numJoints();
  if (q.size() != n || qd.size() != n || qdd.size() != n)
    throw std::invalid_argument("inverse dynamics derivatives: q, qd and qdd must have " + std::to_string(n) +
                                " entries, not " + std::to_string(q.size()) + ", " + std::to_string(qd.size()) +
                                " and " + std::to_string(qdd.size()));
}
// x = (q, qd, qdd) stacked by kind.
double stacked(const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& qd,
               const Eigen::Ref<const Eigen::VectorXd>& qdd, int k) {
  const int n = static_cast<int>(q.size());
  return k < n ? q[k] : k < 2 * n ? qd[k - n] : qdd[k - 2 * n];
}
}  // namespace

Eigen::VectorXd PinTreeDynamics::inverseDynamicsJacobian(const Eigen::Ref<const Eigen::VectorXd>& q,
                                                         const Eigen::Ref<const Eigen::VectorXd>& qd,
                                                         const Eigen::Ref<const Eigen::VectorXd>& qdd,
                                                         Eigen::MatrixXd& jacobian) const {
  require_state(*this, q, qd, qdd);
  using D = Dual<double>;
  const int n = numJoints();
  std::vector<D> x(static_cast<std::size_t>(3 * n)), tau(static_cast<std::size_t>(n));
  ScratchOf<D> scratch;
  jacobian.resize(n, 3 * n);
  Eigen::VectorXd out(n);
  for (int c = 0; c < 3 * n; ++c) {  // one pass per entry of x, its infinitesimal on that entry
    for (int k = 0; k < 3 * n; ++k) x[static_cast<std::size_t>(k)] = D(stacked(q, qd, qdd, k), k == c ? 1.0 : 0.0);
    inverseDynamicsOf<D>(scratch, x.data(), x.data() + n, x.data() + 2 * n, tau.data());
    for (int i = 0; i < n; ++i) jacobian(i, c) = tau[static_cast<std::size_t>(i)].derivative;
  }
  for (int i = 0; i < n; ++i) out[i] = tau[static_cast<std::size_t>(i)].value;
  return out;
}

Eigen::MatrixXd PinTreeDynamics::inverseDynamicsHessian(const Eigen::Ref<const Eigen::VectorXd>& q,
                                                        const Eigen::Ref<const Eigen::VectorXd>& qd,
                                                        const Eigen::Ref<const Eigen::VectorXd>& qdd,
                                                        const Eigen::Ref<const Eigen::VectorXd>& w) const {
  require_state(*this, q, qd, qdd);
  const int n = numJoints();
  if (w.size() != n)
    throw std::invalid_argument("inverse dynamics Hessian: the weights must have " + std::to_string(n) + " entries");
  using H = Dual<Dual<double>>;
  std::vector<H> x(static_cast<std::size_t>(3 * n)), tau(static_cast<std::size_t>(n));
  ScratchOf<H> scratch;
  Eigen::MatrixXd hessian = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (int a = 0; a < 3 * n; ++a)
    for (int b = 0; b <= a; ++b) {
      if (a >= 2 * n && b >= n) continue;  // qdd-qd and qdd-qdd: tau is linear in qdd
      // x + e1 delta_a + e2 delta_b: the e1 e2 coefficient of tau is d2 tau / dx_a dx_b.
      for (int k = 0; k < 3 * n; ++k)
        x[static_cast<std::size_t>(k)] = H(Dual<double>(stacked(q, qd, qdd, k), k == a ? 1.0 : 0.0),
                                           Dual<double>(k == b ? 1.0 : 0.0, 0.0));
      inverseDynamicsOf<H>(scratch, x.data(), x.data() + n, x.data() + 2 * n, tau.data());
      double sum = 0.0;
      for (int i = 0; i < n; ++i) sum += w[i] * tau[static_cast<std::size_t>(i)].derivative.derivative;
      hessian(a, b) = hessian(b, a) = sum;
    }
  return hessian;
}

}  // namespace flatsos::plugin
