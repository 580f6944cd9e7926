#pragma once
// Flat outputs y = [q; Y], Y = E Phi_S(L_S) (docs/method/flatness.md), and the maps between muscle
// states and flat outputs with their derivatives.
//
// A FlatOutputMap is a value: it shares its (immutable) model and owns its matrices, so a copy
// or a temporary can never leave a dangling reference behind, and its const members are safe
// from several threads. Inverse dynamics go through a plugin::ModelWorkspace the caller owns;
// the overloads without one make a temporary workspace (tens of microseconds) per call.
//
// C(q) = [R(q); E] couples them: tau = R(q) F (R: the moment arms, N x m) and Y = E F, so
// F = C(q)^-1 [tau; Y] = C_tau(q) tau + C_Y(q) Y. With constant moment arms C is one matrix; with
// posture-dependent paths it follows the joint motion, and Assumption 1 must hold in every
// posture: the map checks it on a grid over the joint ranges when it is built.
//
// Inverse map (flat outputs -> muscle states and excitations) at one time, from the joint jet
// (q and its first four time derivatives) and the flat-output jet (Y, dY, ddY):
//   tau, dtau, ddtau from the model's inverse dynamics along the joint motion (eighth-order
//   central differences in time of tau(t) = ID(q(t), qd(t), qdd(t)) on the jet's Taylor curve);
//   F and its two time derivatives from ForceJetMap; L_S = Phi_S^-1(F); dL_S = dF / Phi_S';
//   L(q) and its time derivatives exactly from the muscle paths; a and da/dt by the analytic
//   chain rule (muscles/muscle_inverse.hpp); n from the inverse activation dynamics. No
//   numerical differentiation of a.
// Forward map (state -> flat outputs and the derivatives the state determines): q, qd, qdd,
//   q''' , Y, dY from (q, qd, L_S, a) with the same laws the Simbody force element uses.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "flatsos/muscles/muscle_inverse.hpp"
#include "flatsos/planner/effort.hpp"
#include "flatsos/planner/flat_output_choice.hpp"
#include "flatsos/plugin/model/model_workspace.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace flatsos::planner {

/// Derivatives 0..K-1 of a vector signal at one time, one column per order (N x K).
using Jet = Eigen::MatrixXd;

/// Joint torques and their first two time derivatives (N x 3).
struct TorqueJet {
  Eigen::MatrixXd tau;  ///< columns tau, dtau/dt, d2tau/dt2 (N m, N m/s, N m/s^2)
};

/// Why an inverse-map point is outside a muscle's valid domain (kind None: inside). Kept as a
/// value, not a text, so the map allocates nothing; describe() gives the words.
struct DomainViolation {
  enum class Kind {
    None,
    SlackTendon,                    ///< value: the planned tendon force, N (<= 0)
    FiberCollapsed,                 ///< value: a pennated muscle's length along the tendon, m (<= 0)
    NoForceCapacity,                ///< value: the shortening velocity, m/s (>= Vmax)
    ForceRatioBeyondExactRange,     ///< value: the force ratio z; limit: the exact range's end
    ActivationOutsideUnitInterval,  ///< value: the activation
    ActivationBelowFloor,           ///< value: the activation; limit: the forward model's floor
    ExcitationUnattainable,         ///< value: da/dt, 1/s, that no excitation gives
    ExcitationOutsideUnitInterval,  ///< value: the excitation
  };
  Kind kind = Kind::None;
  double value = 0.0;
  double limit = 0.0;
  bool violated() const { return kind != Kind::None; }
  /// E.g. "activation 1.7 outside (0, 1]"; empty for None.
  std::string describe() const;
  /// How far outside the domain (in the kind's own quantity; +inf for non-finite values), so
  /// violations of one kind can be ranked; 0 for None.
  double excess() const;
};

/// Muscle quantities from the inverse map at one time (one entry per muscle).
struct MusclePoint {
  Eigen::VectorXd tendon_force_N, tendon_force_rate_N_per_s;
  Eigen::VectorXd tendon_length_m, tendon_length_rate_m_per_s;
  Eigen::VectorXd fiber_length_m, shortening_velocity_m_per_s;
  Eigen::VectorXd force_ratio;  ///< z = g(u)
  Eigen::VectorXd activation, activation_rate_per_s;
  Eigen::VectorXd excitation;   ///< larger root of the inverse activation dynamics
  /// Per muscle: inside the valid domain, or why not (slack tendon, collapsed fibre, u >= Vmax, z beyond the
  /// exact force-velocity range, a outside (0, 1] or below the floor, n outside [0, 1] or
  /// unattainable).
  std::vector<DomainViolation> domain_violation;
  bool inDomain() const;
};

/// Reusable storage for FlatOutputMap::torqueJetsOnGrid (sized on first use; allocation-free
/// afterwards for the same grid size).
struct TorqueJetGrid {
  std::vector<TorqueJet> jets;  ///< the result: one jet per grid time
  Eigen::MatrixXd fine_torques_N_m;  ///< scratch: inverse dynamics on the refined grid (N x points)
  Jet joint_jet;                     ///< scratch: q, qd, qdd at one time (N x 3)
  Jet limit_joint_jet;               ///< scratch: q .. q''' at a grid time (N x 4), joint limits only
  Eigen::MatrixXd limit_jet_N_m;     ///< scratch: the limit torques' jet there (N x 3)
};

/// How the tendon forces' jet follows the torque and flat-output jets at one point of a joint
/// motion. Differentiating C(q) F = [tau; Y] twice in time gives, with C^-1 = [C_tau | C_Y] and
/// K_i = C^-1 d^iC/dt^i = C_tau d^iR/dt^i,
///   F = v_0,  dF = v_1 + W10 v_0,  ddF = v_2 + W21 v_1 + W20 v_0,  v_i = C_tau tau^(i) + C_Y Y^(i),
/// W10 = -K1, W21 = -2 K1, W20 = 2 K1^2 - K2. With constant moment arms, or at a posture at rest
/// (a joint jet without rates), every W is 0 (empty).
struct ForceJetMap {
  Eigen::MatrixXd Ctau, CY;       ///< m x N, m x p at this posture
  Eigen::MatrixXd W10, W20, W21;  ///< m x m; empty where they are 0 (above)
  Eigen::MatrixXd R1, R2;         ///< N x m: dR/dt, d2R/dt2 along the motion (K_i = C_tau R_i); empty likewise
  /// Whether the map changes along the motion here (the W are not 0).
  bool varies() const { return W10.size() > 0; }
  /// dC_Y/dt = W10 C_Y and d2C_Y/dt2 = W20 C_Y along the motion (m x p each; zero with constant
  /// moment arms), through the rank-N factors: O(m N p), where W C_Y is O(m^2 p).
  void flatOutputColumnRates(Eigen::MatrixXd& CY1, Eigen::MatrixXd& CY2) const;
  /// Replaces v_0, v_1, v_2 (m x c each) by the F-jet orders they give: the formulas above.
  void mix(Eigen::MatrixXd& v0, Eigen::MatrixXd& v1, Eigen::MatrixXd& v2) const;
  /// The tendon-force jet (m x 3: F, dF, ddF) from the torque jet (N x 3) and the flat-output
  /// jet (p x 2..3; a missing ddY is 0).
  Eigen::MatrixXd forceJet(const Eigen::MatrixXd& tau, const Eigen::MatrixXd& Y) const;
};

/// The flat outputs and derivatives that a muscle state determines.
struct FlatState {
  Eigen::MatrixXd q;  ///< N x 4: q, qd, qdd, q''' (rad, rad/s, ...)
  Eigen::MatrixXd Y;  ///< p x 2: Y, dY (N, N/s)
};

/// Muscle state of a model at one time (description order).
struct MuscleState {
  Eigen::VectorXd q_rad, qd_rad_per_s, tendon_length_m, activation;
};

/// The muscle state of a Simbody State of `model` (q, qd, tendon lengths, activations).
MuscleState muscle_state_of(const plugin::MusculoskeletalModel& model, const SimTK::State& state);

/// The effort w^T F = w^T C_tau(q) tau + w^T C_Y(q) Y split at one posture: the flat outputs'
/// weights C_Y^T w (p) and the torques' C_tau^T w (N).
struct EffortSplit {
  Eigen::VectorXd flat_outputs, torques;
};

class FlatOutputMap {
 public:
  /// E from the model file's flat_outputs, or, when it gives none, the E choose_flat_outputs
  /// finds (flat_output_choice.hpp). Throws FlatnessError naming each violated condition of
  /// Assumption 1 (E shape, C singular, rows of E not summing to 1, 1 - C_tau s_tau > 0); with
  /// posture-dependent moment arms, at the first posture of a grid over the joint ranges
  /// (plugin/model/posture_grid.hpp) where one fails, named in degrees.
  /// Throws std::invalid_argument for a null model.
  explicit FlatOutputMap(std::shared_ptr<const plugin::MusculoskeletalModel> model);
  /// The given E (the model's flat_outputs ignored), checked as above.
  FlatOutputMap(std::shared_ptr<const plugin::MusculoskeletalModel> model, Eigen::MatrixXd E);
  /// As the first constructor, but E serves (is chosen and checked over) the postures of
  /// `region` only, one range per joint inside the joint ranges (task_region.hpp): for tasks
  /// that stay there when no E serves the whole ranges. Throws as above and
  /// std::invalid_argument for a region of the wrong size or outside the ranges.
  static FlatOutputMap overRegion(std::shared_ptr<const plugin::MusculoskeletalModel> model, plugin::JointRanges region);
  /// These flat outputs (E, names, whether the library chose them: hence the same kind of
  /// effort) on another model of as many joints and muscles, e.g. other muscle strengths,
  /// checked as above; the choice's margin is the one scored for this map's model.
  FlatOutputMap withModel(std::shared_ptr<const plugin::MusculoskeletalModel> model) const;

  const plugin::MusculoskeletalModel& model() const { return *model_; }
  const std::shared_ptr<const plugin::MusculoskeletalModel>& sharedModel() const { return model_; }
  /// Scratch for the calls below that take one (one per thread).
  plugin::ModelWorkspace makeWorkspace() const { return model_->makeWorkspace(); }
  int numJoints() const { return joints_; }
  int numMuscles() const { return muscles_; }
  int numFlatOutputs() const { return static_cast<int>(E_.rows()); }
  const Eigen::MatrixXd& E() const { return E_; }
  /// E with its row names, whether the library chose it, and its margin over the joint ranges.
  const FlatOutputChoice& flatOutputs() const { return flat_outputs_; }
  /// True when C does not depend on posture (every muscle path of order <= 1).
  bool hasConstantMomentArms() const { return constant_; }
  /// The constant A = R, C, C_tau (m x N) and C_Y (m x p): constant moment arms only; with
  /// posture-dependent ones they throw std::logic_error (use forceJetMap).
  const Eigen::MatrixXd& A() const;
  const Eigen::MatrixXd& C() const;
  const Eigen::MatrixXd& Ctau() const;
  const Eigen::MatrixXd& CY() const;
  /// The effort weights w (m): the cost is the integral of w^T F (the model's effort_weights).
  /// By default E^T 1, the sum of the flat outputs (whose torque part is 0 since E C_tau = 0),
  /// when E was given; 1 / Fmax, the sum of normalized tendon forces, when the library chose E.
  const Eigen::VectorXd& effortWeights() const { return effort_weights_; }
  /// The weights the planners' linear programs price tendon forces with: effortWeights(), but
  /// where muscles are tied (the same moment arms in every posture and the same weight, so every
  /// split of their load costs the same) each earlier muscle of the group 1e-3 dearer than the
  /// next: a unique optimum instead of a face whose vertices the LPs jump between.
  const Eigen::VectorXd& effortPricingWeights() const { return pricing_weights_; }
  /// How the weights were set: never EffortWeights::Kind::Default (resolved as above).
  plugin::EffortWeights::Kind effortKind() const { return effort_kind_; }
  /// True for the paper's weights E^T 1: then w^T F is exactly the sum of the flat outputs.
  bool effortIsFlatOutputSum() const;
  /// The cost's unit: "s" for normalized tendon forces (w = 1 / Fmax), "N s" otherwise (weights
  /// taken as dimensionless).
  std::string effortUnit() const;
  /// The effort the flatness planners minimize: w^T F with the weights above (effort.hpp).
  std::shared_ptr<const Effort> effort() const;
  /// This map minimizing `effort` instead of the model's weights. The flatness planners solve
  /// linear programs: throws std::invalid_argument naming an effort that is not linear in the
  /// tendon forces (the collocation reference takes any) or whose weights do not fit the model.
  FlatOutputMap withEffort(std::shared_ptr<const Effort> effort) const;
  /// w^T F split into its flat-output and torque parts at posture q (constant with constant arms).
  EffortSplit effortSplit(const Eigen::VectorXd& q_rad) const;
  /// The moment arms R(q) (N x m) in any posture.
  Eigen::MatrixXd momentArms(const Eigen::VectorXd& q_rad) const;
  /// C_tau, C_Y and the W of ForceJetMap at a point of a joint motion (q_jet N x 1..5: q, qd,
  /// qdd, ...; missing rates are 0). Throws FlatnessError, naming the posture, where C(q) is
  /// singular.
  ForceJetMap forceJetMap(const Jet& q_jet) const;
  /// forceJetMap(q_jet).forceJet(tau, Y) without forming C^-1 (what the inverse map needs): one
  /// LU of C and three solves, C F' = [tau' - R' F; Y'], C F'' = [tau'' - 2 R' F' - R'' F; Y''].
  /// Same errors.
  Eigen::MatrixXd forceJet(const Jet& q_jet, const Eigen::MatrixXd& tau, const Eigen::MatrixXd& Y) const;

  /// Checks Assumption 1 for a pair (A, E); throws FlatnessError listing every failure.
  static void checkAssumption1(const Eigen::MatrixXd& A, const Eigen::MatrixXd& E);
  /// The failures of Assumption 1 at one posture (empty when it holds), as checkAssumption1
  /// words them, prefixed with the posture: for checks along a planned path.
  std::string assumption1FailureAt(const Eigen::VectorXd& q_rad) const;
  /// The force-jet map at q_jet into `map` where Assumption 1 holds there (returns ""), else
  /// assumption1FailureAt's words: one coupling inverse for both, since condition 3 is C_Y's row
  /// sums (C 1 = [s_tau; 1] as E's rows sum to 1, so 1 - C_tau s_tau = C_Y 1). Within 1e-9 of
  /// failing, assumption1FailureAt decides.
  std::string forceJetMapWhereFlat(const Jet& q_jet, ForceJetMap& map) const;

  /// tau(q, qd, qdd): the torques the muscles must supply (MusculoskeletalModel::inverseDynamics).
  Eigen::VectorXd torque(plugin::ModelWorkspace& workspace, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                         const Eigen::VectorXd& qdd) const;
  Eigen::VectorXd torque(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) const;
  /// tau and its first two time derivatives along a joint motion with the given jet
  /// (N x 5: q .. q''''). Columns beyond those given are taken as 0. Exact: dual numbers through
  /// the pin tree's inverse dynamics, the joint limits' torques included.
  TorqueJet torqueJet(plugin::ModelWorkspace& workspace, const Jet& q_jet) const;
  TorqueJet torqueJet(const Jet& q_jet) const;

  /// Torque jets at the `count` uniform times t0 + i h along a joint motion given as a function
  /// of time (q, qd, qdd, q''' at t: N x 4; q''' is read for a model with joint limits). The rigid
  /// bodies' share by eighth-order differences in time of their (analytic) inverse dynamics, where
  /// neighbouring times share their calls: about one call per time (the grid is refined
  /// internally to a step <= 10 ms); the joint limits' share (only twice continuously
  /// differentiable) exactly.
  template <class JointJetAt>
  std::vector<TorqueJet> torqueJetsOnGrid(plugin::ModelWorkspace& workspace, const JointJetAt& jet_at, double t0,
                                          double h, int count) const;
  /// The same into reusable storage; `write_jet(t, jet)` writes q and its derivatives at t into
  /// every column of the given N x k matrix (k = 3, or 4 for the joint limits' jets). Allocates
  /// nothing once `grid` has been used for this count.
  template <class WriteJointJet>
  void torqueJetsOnGrid(plugin::ModelWorkspace& workspace, const WriteJointJet& write_jet, double t0, double h,
                        int count, TorqueJetGrid& grid) const;

  /// Inverse map at one time: q_jet N x 5 (q..q''''), Y_jet p x 3 (Y, dY, ddY).
  MusclePoint inverse(plugin::ModelWorkspace& workspace, const Jet& q_jet, const Jet& Y_jet) const;
  MusclePoint inverse(const Jet& q_jet, const Jet& Y_jet) const;
  /// Same with a precomputed torque jet (no inverse dynamics: no workspace).
  MusclePoint inverseFromTorque(const Jet& q_jet, const TorqueJet& tau, const Jet& Y_jet) const;
  /// The same into `out`, reusing its storage (allocates nothing once `out` holds m muscles).
  void inverseFromTorque(const Jet& q_jet, const TorqueJet& tau, const Jet& Y_jet, MusclePoint& out) const;

  /// Musculotendon length of muscle j and its first two time derivatives along a joint motion
  /// (q_jet N x 1..5; missing rates are 0), exact for any path polynomial.
  muscles::SecondOrderJet pathLengthJet(int muscle, const Jet& q_jet) const;
  /// Its derivatives with respect to the joint jet's entries: out(k, 5 r + l) = d (d^k L / dt^k)
  /// / d (d^l q_r / dt^l), k = 0..2, l = 0..4 (out: 3 x 5N). Constant moment arms only (what a
  /// free joint path needs); std::logic_error otherwise.
  void pathLengthJetGradient(int muscle, const Jet& q_jet, Eigen::Ref<Eigen::MatrixXd> out) const;

  /// Forward map of a muscle state. Throws std::invalid_argument for sizes or NaN.
  FlatState forward(plugin::ModelWorkspace& workspace, const MuscleState& s) const;
  FlatState forward(const MuscleState& s) const;

 private:
  FlatOutputMap(std::shared_ptr<const plugin::MusculoskeletalModel> model, FlatOutputChoice flat_outputs);
  const Eigen::MatrixXd& requireConstant(const Eigen::MatrixXd& matrix, const char* name) const;
  void checkAssumption1OverRanges() const;
  void setPricingWeights();  // from effort_weights_ and the model's tied muscles

  std::shared_ptr<const plugin::MusculoskeletalModel> model_;
  bool constant_ = true;
  int joints_ = 0, muscles_ = 0;
  FlatOutputChoice flat_outputs_;
  Eigen::MatrixXd A_, E_, C_, Ctau_, CY_;  // A_ .. CY_: constant moment arms only
  plugin::EffortWeights::Kind effort_kind_ = plugin::EffortWeights::Kind::FlatOutputs;
  Eigen::VectorXd effort_weights_;
  Eigen::VectorXd pricing_weights_;
};

namespace detail {
/// Eighth-order central-difference weights (offsets -4..4) and the largest step used.
extern const double kFirstDerivativeWeights[9];
extern const double kSecondDerivativeWeights[9];
constexpr double kMaxJetStep_s = 1e-2;
}  // namespace detail

template <class WriteJointJet>
void FlatOutputMap::torqueJetsOnGrid(plugin::ModelWorkspace& workspace, const WriteJointJet& write_jet, double t0,
                                     double h, int count, TorqueJetGrid& grid) const {
  if (count < 1 || !(h > 0.0)) throw std::invalid_argument("torque jets on a grid: need count >= 1 and h > 0");
  const int n = numJoints();
  const int sub = std::max(1, static_cast<int>(std::ceil(h / detail::kMaxJetStep_s - 1e-12)));
  const double hf = h / sub;
  const int fine = (count - 1) * sub + 9;  // fine points k = -4 .. (count - 1) sub + 4
  grid.fine_torques_N_m.resize(n, fine);    // no-ops when the sizes are unchanged
  grid.joint_jet.resize(n, 3);
  grid.jets.resize(static_cast<std::size_t>(count));
  for (int k = 0; k < fine; ++k) {
    write_jet(t0 + (k - 4) * hf, grid.joint_jet);
    model_->rigidBodyInverseDynamics(workspace, grid.joint_jet.col(0), grid.joint_jet.col(1), grid.joint_jet.col(2),
                                     grid.fine_torques_N_m.col(k));
  }
  for (int i = 0; i < count; ++i) {
    Eigen::MatrixXd& tau = grid.jets[static_cast<std::size_t>(i)].tau;
    tau.setZero(n, 3);
    const int c = i * sub + 4;
    tau.col(0) = grid.fine_torques_N_m.col(c);
    for (int k = -4; k <= 4; ++k) {
      tau.col(1) += detail::kFirstDerivativeWeights[k + 4] / hf * grid.fine_torques_N_m.col(c + k);
      tau.col(2) += detail::kSecondDerivativeWeights[k + 4] / (hf * hf) * grid.fine_torques_N_m.col(c + k);
    }
    if (model_->hasJointLimits()) {
      grid.limit_joint_jet.resize(n, 4);
      grid.limit_jet_N_m.resize(n, 3);
      write_jet(t0 + i * h, grid.limit_joint_jet);
      model_->pinTree().jointLimitTorqueJet(grid.limit_joint_jet, grid.limit_jet_N_m);
      tau -= grid.limit_jet_N_m;
    }
  }
}

template <class JointJetAt>
std::vector<TorqueJet> FlatOutputMap::torqueJetsOnGrid(plugin::ModelWorkspace& workspace, const JointJetAt& jet_at,
                                                       double t0, double h, int count) const {
  TorqueJetGrid grid;
  torqueJetsOnGrid(
      workspace,
      [&](double t, Jet& out) {
        const Jet jet = jet_at(t);
        if (jet.cols() < out.cols())
          throw std::invalid_argument("torque jets on a grid: the joint jet has " + std::to_string(jet.cols()) +
                                      " columns, " + std::to_string(out.cols()) + " are needed");
        out = jet.leftCols(out.cols());
      },
      t0, h, count, grid);
  return std::move(grid.jets);
}

}  // namespace flatsos::planner
