#include "flatsos/planner/flat_outputs.hpp"

#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include <Eigen/Dense>

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/muscles/muscle_inverse.hpp"
#include "flatsos/plugin/model/posture_grid.hpp"

namespace flatsos::planner {

namespace fm = flatsos::muscles;

// Eighth-order central differences at offsets -4h..4h (Fornberg's weights).
const double detail::kFirstDerivativeWeights[9] = {1.0 / 280, -4.0 / 105, 1.0 / 5, -4.0 / 5, 0.0,
                                                   4.0 / 5,   -1.0 / 5,   4.0 / 105, -1.0 / 280};
const double detail::kSecondDerivativeWeights[9] = {-1.0 / 560, 8.0 / 315, -1.0 / 5, 8.0 / 5, -205.0 / 72,
                                                    8.0 / 5,    -1.0 / 5,  8.0 / 315, -1.0 / 560};

MuscleState muscle_state_of(const plugin::MusculoskeletalModel& model, const SimTK::State& state) {
  return {model.jointAngles(state), model.jointSpeeds(state), model.tendonLengths(state), model.activations(state)};
}

bool MusclePoint::inDomain() const {
  for (const auto& v : domain_violation)
    if (v.violated()) return false;
  return true;
}

double DomainViolation::excess() const {
  if (!std::isfinite(value)) return std::numeric_limits<double>::infinity();
  switch (kind) {
    case Kind::None: return 0.0;
    case Kind::SlackTendon:
    case Kind::FiberCollapsed: return -value;
    case Kind::NoForceCapacity:
    case Kind::ForceRatioBeyondExactRange: return value - limit;
    case Kind::ActivationOutsideUnitInterval:
    case Kind::ExcitationOutsideUnitInterval: return value > 1.0 ? value - 1.0 : -value;
    case Kind::ActivationBelowFloor: return limit - value;
    case Kind::ExcitationUnattainable: return std::abs(value);
  }
  return 0.0;
}

std::string DomainViolation::describe() const {
  std::ostringstream why;
  switch (kind) {
    case Kind::None: return "";
    case Kind::SlackTendon: why << "slack tendon (planned tendon force " << value << " N <= 0)"; break;
    case Kind::FiberCollapsed:
      why << "collapsed fibre (the muscle along the tendon is " << value << " m: the tendon is longer than the unit)";
      break;
    case Kind::NoForceCapacity: why << "shortening velocity " << value << " m/s >= Vmax (no force capacity)"; break;
    case Kind::ForceRatioBeyondExactRange:
      why << "force ratio z = " << value << " beyond the forward model's exact range (" << limit << ")";
      break;
    case Kind::ActivationOutsideUnitInterval: why << "activation " << value << " outside (0, 1]"; break;
    case Kind::ActivationBelowFloor: why << "activation " << value << " below the forward model's floor " << limit; break;
    case Kind::ExcitationUnattainable: why << "no excitation gives da/dt = " << value << " 1/s"; break;
    case Kind::ExcitationOutsideUnitInterval: why << "excitation " << value << " outside [0, 1]"; break;
  }
  return why.str();
}

namespace {

// C = [A; E] factorized by partial pivoting (a fraction of the full-pivot LU's time, which
// matters at 40 muscles and a dozen postures per receding-horizon step); where a pivot falls
// below 1e-10 of the largest, the full-pivot LU decides the rank as before, with that threshold.
class CouplingLu {
 public:
  explicit CouplingLu(const Eigen::MatrixXd& C) : partial_(C) {
    const Eigen::VectorXd pivots = partial_.matrixLU().diagonal().cwiseAbs();
    if (pivots.minCoeff() > 1e-10 * pivots.maxCoeff()) return;
    full_.emplace(C);
    full_->setThreshold(1e-10);
  }
  bool invertible() const { return !full_ || full_->isInvertible(); }
  Eigen::Index rank() const { return full_ ? full_->rank() : partial_.rows(); }
  Eigen::MatrixXd inverse() const { return full_ ? Eigen::MatrixXd(full_->inverse()) : Eigen::MatrixXd(partial_.inverse()); }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const {
    return full_ ? Eigen::VectorXd(full_->solve(b)) : Eigen::VectorXd(partial_.solve(b));
  }

 private:
  Eigen::PartialPivLU<Eigen::MatrixXd> partial_;
  std::optional<Eigen::FullPivLU<Eigen::MatrixXd>> full_;
};

// The violated conditions of Assumption 1 for moment arms A and flat outputs E of the right
// shapes (empty: it holds).
std::vector<std::string> assumption1_failures(const Eigen::MatrixXd& A, const Eigen::MatrixXd& E) {
  const Eigen::Index n = A.rows(), m = A.cols();
  if (!A.allFinite() || !E.allFinite()) return {"A and E must be finite"};
  Eigen::MatrixXd C(m, m);
  C << A, E;
  std::vector<std::string> failures;
  for (Eigen::Index i = 0; i < E.rows(); ++i)
    if (std::abs(E.row(i).sum() - 1.0) > 1e-12) {
      std::ostringstream f;
      f << "condition 2: row " << i << " of E sums to " << E.row(i).sum() << ", not 1";
      failures.push_back(f.str());
    }
  const CouplingLu lu(C);
  if (!lu.invertible()) {
    failures.push_back("condition 1: C = [A; E] is singular (rank " + std::to_string(lu.rank()) +
                       " of " + std::to_string(m) + ")");
  } else {
    // C_tau s_tau = C^-1 [s_tau; 0]: one solve instead of the inverse.
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m);
    rhs.head(n) = A.rowwise().sum();
    const Eigen::VectorXd margin = Eigen::VectorXd::Ones(m) - lu.solve(rhs);
    for (Eigen::Index j = 0; j < m; ++j)
      if (!(margin[j] > 0.0)) {
        std::ostringstream f;
        f << "condition 3: 1 - C_tau s_tau = " << margin[j] << " <= 0 for muscle " << j;
        failures.push_back(f.str());
      }
  }
  return failures;
}

std::string join_failures(const std::vector<std::string>& failures) {
  std::string msg = "Assumption 1 violated:";
  for (const auto& f : failures) msg += " " + f + ";";
  return msg;
}

void require_shape(const Eigen::MatrixXd& E, Eigen::Index n, Eigen::Index m) {
  if (E.rows() != m - n || E.cols() != m) {
    std::ostringstream why;
    why << "flat-output matrix E must be (m - N) x m = " << (m - n) << " x " << m << ", got " << E.rows() << " x "
        << E.cols();
    throw FlatnessError(why.str());
  }
}

}  // namespace

void FlatOutputMap::checkAssumption1(const Eigen::MatrixXd& A, const Eigen::MatrixXd& E) {
  require_shape(E, A.rows(), A.cols());
  const std::vector<std::string> failures = assumption1_failures(A, E);
  if (!failures.empty()) throw FlatnessError(join_failures(failures));
}

namespace {
// R and its first two time derivatives along a joint motion (q_jet N x 1..5; missing rates 0),
// exact from each path's jets (the jet's column-major storage is the paths' layout: entry
// [k n + i] is d^k q_i / dt^k).
std::array<Eigen::MatrixXd, 3> moment_arm_jets(const plugin::MusculoskeletalModel& model, const Jet& q_jet) {
  const int n = model.numJoints(), m = model.numMuscles();
  Eigen::MatrixXd jet = Eigen::MatrixXd::Zero(n, 3);
  const Eigen::Index given = std::min<Eigen::Index>(3, q_jet.cols());
  jet.leftCols(given) = q_jet.leftCols(given);
  std::array<Eigen::MatrixXd, 3> R;
  for (auto& r : R) r.resize(n, m);
  Eigen::MatrixXd arm_jet(n, 3);
  for (int j = 0; j < m; ++j) {
    model.musclePath(j).momentArmJets(jet.data(), 3, arm_jet.data());
    for (int k = 0; k < 3; ++k) R[static_cast<std::size_t>(k)].col(j) = arm_jet.col(k);
  }
  return R;
}

const plugin::MusculoskeletalModel& require_model(const std::shared_ptr<const plugin::MusculoskeletalModel>& model) {
  if (!model) throw std::invalid_argument("flat-output map: no model (null pointer)");
  return *model;
}
}  // namespace

namespace {
// The model's own flat outputs, or the library's choice when it gives none.
FlatOutputChoice flat_outputs_of(const plugin::MusculoskeletalModel& model, const plugin::JointRanges& region = {}) {
  const plugin::ModelDescription& d = model.description();
  if (d.flat_outputs.empty()) {
    FlatOutputSearchOptions search;
    search.region = region;
    return choose_flat_outputs(model, search);
  }
  FlatOutputChoice given;
  given.E = d.flatOutputMatrix();
  for (const auto& y : d.flat_outputs) given.names.push_back(y.name);
  given.region = region;
  return given;
}

void require_region_inside_ranges(const plugin::ModelDescription& d, const plugin::JointRanges& region) {
  if (region.size() != d.joints.size())
    throw std::invalid_argument("flat outputs' region: " + std::to_string(region.size()) + " ranges for " +
                                std::to_string(d.joints.size()) + " joints");
  for (std::size_t i = 0; i < region.size(); ++i)
    if (!(region[i][0] <= region[i][1]) || region[i][0] < d.joints[i].range_rad[0] || region[i][1] > d.joints[i].range_rad[1])
      throw std::invalid_argument("flat outputs' region of joint '" + d.joints[i].name + "' (" +
                                  plugin::describe_region(d, region) + ") is not an interval inside its range");
}

FlatOutputChoice given_flat_outputs(Eigen::MatrixXd E) {
  FlatOutputChoice given;
  for (Eigen::Index k = 0; k < E.rows(); ++k) given.names.push_back("y" + std::to_string(k));
  given.E = std::move(E);
  return given;
}

// Postures of the load-time Assumption 1 check (the same budget as the model's own path checks,
// posture_grid.hpp: the ranges' ends at least).
constexpr long kCheckedPostures = 20000;
}  // namespace

FlatOutputMap::FlatOutputMap(std::shared_ptr<const plugin::MusculoskeletalModel> model)
    : FlatOutputMap(model, flat_outputs_of(require_model(model))) {}

FlatOutputMap::FlatOutputMap(std::shared_ptr<const plugin::MusculoskeletalModel> model, Eigen::MatrixXd E)
    : FlatOutputMap(std::move(model), given_flat_outputs(std::move(E))) {}

FlatOutputMap FlatOutputMap::overRegion(std::shared_ptr<const plugin::MusculoskeletalModel> model,
                                        plugin::JointRanges region) {
  const plugin::MusculoskeletalModel& m = require_model(model);
  require_region_inside_ranges(m.description(), region);
  return FlatOutputMap(model, flat_outputs_of(m, region));
}

FlatOutputMap FlatOutputMap::withModel(std::shared_ptr<const plugin::MusculoskeletalModel> model) const {
  const plugin::MusculoskeletalModel& m = require_model(model);
  if (m.numJoints() != joints_ || m.numMuscles() != muscles_)
    throw std::invalid_argument("flat outputs of a model of " + std::to_string(joints_) + " joints and " +
                                std::to_string(muscles_) + " muscles given to one of " + std::to_string(m.numJoints()) +
                                " and " + std::to_string(m.numMuscles()));
  return FlatOutputMap(std::move(model), flat_outputs_);
}

FlatOutputMap::FlatOutputMap(std::shared_ptr<const plugin::MusculoskeletalModel> model, FlatOutputChoice flat_outputs)
    : model_(std::move(model)), flat_outputs_(std::move(flat_outputs)), E_(flat_outputs_.E) {
  const plugin::MusculoskeletalModel& m = require_model(model_);
  joints_ = m.numJoints();
  muscles_ = m.numMuscles();
  constant_ = m.hasConstantMomentArms();
  if (E_.rows() == 0) throw FlatnessError("the model '" + m.description().name + "' defines no flat_outputs (E)");
  require_shape(E_, joints_, muscles_);
  const plugin::EffortWeights& weights = m.description().effort_weights;
  effort_kind_ = weights.kind;
  if (effort_kind_ == plugin::EffortWeights::Kind::Default)
    effort_kind_ = flat_outputs_.automatic ? plugin::EffortWeights::Kind::NormalizedTendonForce
                                           : plugin::EffortWeights::Kind::FlatOutputs;
  switch (effort_kind_) {
    case plugin::EffortWeights::Kind::Default:
    case plugin::EffortWeights::Kind::FlatOutputs: effort_weights_ = E_.transpose() * Eigen::VectorXd::Ones(E_.rows()); break;
    case plugin::EffortWeights::Kind::NormalizedTendonForce:
      effort_weights_.resize(muscles_);
      for (int j = 0; j < muscles_; ++j) effort_weights_[j] = 1.0 / m.muscle(j).getParameters().max_isometric_force_N;
      break;
    case plugin::EffortWeights::Kind::PerMuscle: effort_weights_ = weights.per_muscle; break;
  }
  setPricingWeights();
  if (!constant_) {
    // One pass for the margin; a second one only to name the first failing posture.
    if (!flat_outputs_.automatic) flat_outputs_.margin = flat_output_margin(m, E_, kCheckedPostures, flat_outputs_.region);
    const FlatOutputMargin& margin = flat_outputs_.margin;
    if (!margin.holds() || !assumption1_failures(m.momentArmMatrix(margin.posture_rad), E_).empty()) {
      checkAssumption1OverRanges();
      // Not reached unless the two passes disagree at round-off: still a failure, said so.
      throw FlatnessError("model '" + m.description().name + "': Assumption 1 fails: the smallest entry of C_Y(q) 1 is " +
                          std::to_string(margin.margin) + " " + assumption1FailureAt(margin.posture_rad));
    }
    return;
  }
  A_ = m.momentArmMatrix();
  checkAssumption1(A_, E_);
  if (!flat_outputs_.automatic) flat_outputs_.margin = flat_output_margin(m, E_, 1);
  C_.resize(numMuscles(), numMuscles());
  C_ << A_, E_;
  const Eigen::MatrixXd Cinv = C_.fullPivLu().inverse();
  Ctau_ = Cinv.leftCols(numJoints());
  CY_ = Cinv.rightCols(numFlatOutputs());
}

void FlatOutputMap::checkAssumption1OverRanges() const {
  const plugin::ModelDescription& d = model_->description();
  const std::vector<int> joints = plugin::posture_dependent_joints(d);
  const plugin::JointRanges& region = flat_outputs_.region;
  const std::string where = region.empty() ? "the joint ranges" : "the flat outputs' region " + plugin::describe_region(d, region);
  plugin::for_each_posture(
      d, joints, kCheckedPostures,
      [&](const Eigen::VectorXd& q) {
        const std::vector<std::string> failures = assumption1_failures(model_->momentArmMatrix(q), E_);
        if (!failures.empty())
          throw FlatnessError("model '" + d.name + "', C(q) = [R(q); E] at " + plugin::describe_posture(d, joints, q) +
                              " (a posture in " + where + "): " + join_failures(failures));
      },
      region);
}

std::string FlatOutputMap::assumption1FailureAt(const Eigen::VectorXd& q) const {
  const std::vector<std::string> failures =
      assumption1_failures(constant_ ? A_ : model_->momentArmMatrix(q), E_);
  if (failures.empty()) return "";
  return "at " + plugin::describe_posture(model_->description(), q) + ": " + join_failures(failures);
}

std::string FlatOutputMap::forceJetMapWhereFlat(const Jet& q_jet, ForceJetMap& map) const {
  try {
    map = forceJetMap(q_jet);
  } catch (const FlatnessError&) {  // C(q) singular: condition 1
    const std::string failure = assumption1FailureAt(q_jet.col(0));
    return failure.empty() ? "at " + plugin::describe_posture(model_->description(), q_jet.col(0)) + ": C(q) is singular"
                           : failure;
  }
  if ((map.CY.rowwise().sum().array() > 1e-9).all()) return "";
  return assumption1FailureAt(q_jet.col(0));
}

const Eigen::MatrixXd& FlatOutputMap::requireConstant(const Eigen::MatrixXd& matrix, const char* name) const {
  if (!constant_)
    throw std::logic_error(std::string("flat-output map: ") + name + " is constant only with constant moment arms; model '" +
                           model_->description().name + "' has posture-dependent ones (use forceJetMap(q))");
  return matrix;
}

const Eigen::MatrixXd& FlatOutputMap::A() const { return requireConstant(A_, "A"); }
const Eigen::MatrixXd& FlatOutputMap::C() const { return requireConstant(C_, "C"); }
const Eigen::MatrixXd& FlatOutputMap::Ctau() const { return requireConstant(Ctau_, "C_tau"); }
const Eigen::MatrixXd& FlatOutputMap::CY() const { return requireConstant(CY_, "C_Y"); }

Eigen::MatrixXd FlatOutputMap::momentArms(const Eigen::VectorXd& q) const {
  return constant_ ? A_ : model_->momentArmMatrix(q);
}

ForceJetMap FlatOutputMap::forceJetMap(const Jet& q_jet) const {
  const int n = numJoints(), m = numMuscles();
  if (q_jet.rows() != n || q_jet.cols() < 1)
    throw std::invalid_argument("force jet map: the joint jet must be N x (1..5)");
  ForceJetMap map;
  if (constant_) {
    map.Ctau = Ctau_;
    map.CY = CY_;
    return map;
  }
  const std::array<Eigen::MatrixXd, 3> R = moment_arm_jets(*model_, q_jet);
  Eigen::MatrixXd C(m, m);
  C << R[0], E_;
  const CouplingLu lu(C);
  if (!lu.invertible()) {
    throw FlatnessError("C(q) = [R(q); E] is singular at " + plugin::describe_posture(model_->description(), q_jet.col(0)) +
                        " (rank " + std::to_string(lu.rank()) + " of " + std::to_string(m) + "): the flat outputs "
                        "do not determine the tendon forces there");
  }
  const Eigen::MatrixXd Cinv = lu.inverse();
  map.Ctau = Cinv.leftCols(n);
  map.CY = Cinv.rightCols(numFlatOutputs());
  // A posture at rest (no joint rates: the receding horizon's grid asks so) has R1 = R2 = 0, so
  // every W is 0: left empty, as with constant moment arms.
  const Eigen::Index rates = std::min<Eigen::Index>(2, q_jet.cols() - 1);
  if (rates == 0 || q_jet.middleCols(1, rates).isZero(0.0)) return map;
  const Eigen::MatrixXd K1 = map.Ctau * R[1], K2 = map.Ctau * R[2];
  map.W10 = -K1;
  map.W21 = -2.0 * K1;
  // K1 K1 = C_tau (R' C_tau) R': the N x N middle keeps it O(m^2 N), not O(m^3).
  const Eigen::MatrixXd middle = R[1] * map.Ctau;
  map.W20.noalias() = 2.0 * map.Ctau * (middle * R[1]);
  map.W20 -= K2;
  map.R1 = R[1];
  map.R2 = R[2];
  return map;
}

Eigen::MatrixXd FlatOutputMap::forceJet(const Jet& q_jet, const Eigen::MatrixXd& tau, const Eigen::MatrixXd& Y) const {
  const int n = numJoints(), m = numMuscles();
  if (constant_) return forceJetMap(q_jet).forceJet(tau, Y);
  if (q_jet.rows() != n || q_jet.cols() < 1)
    throw std::invalid_argument("force jet: the joint jet must be N x (1..5)");
  const std::array<Eigen::MatrixXd, 3> R = moment_arm_jets(*model_, q_jet);
  Eigen::MatrixXd C(m, m);
  C << R[0], E_;
  const CouplingLu lu(C);
  if (!lu.invertible()) return forceJetMap(q_jet).forceJet(tau, Y);  // throws, naming the posture
  Eigen::MatrixXd F(m, 3);
  Eigen::VectorXd rhs(m);
  rhs << tau.col(0), Y.col(0);
  F.col(0) = lu.solve(rhs);
  rhs << tau.col(1) - R[1] * F.col(0), Y.col(1);
  F.col(1) = lu.solve(rhs);
  rhs.head(n) = tau.col(2) - 2.0 * R[1] * F.col(1) - R[2] * F.col(0);
  if (Y.cols() > 2) rhs.tail(m - n) = Y.col(2);
  else rhs.tail(m - n).setZero();
  F.col(2) = lu.solve(rhs);
  return F;
}

Eigen::VectorXd FlatOutputMap::torque(plugin::ModelWorkspace& ws, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                      const Eigen::VectorXd& qdd) const {
  return model_->inverseDynamics(ws, q, qd, qdd);
}

Eigen::VectorXd FlatOutputMap::torque(const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                      const Eigen::VectorXd& qdd) const {
  return model_->inverseDynamics(q, qd, qdd);
}

TorqueJet FlatOutputMap::torqueJet(const Jet& q_jet) const {
  plugin::ModelWorkspace ws = makeWorkspace();
  return torqueJet(ws, q_jet);
}

TorqueJet FlatOutputMap::torqueJet(plugin::ModelWorkspace&, const Jet& q_jet) const {
  if (q_jet.rows() != numJoints() || q_jet.cols() < 3 || q_jet.cols() > 5)
    throw std::invalid_argument("joint jet must be N x (3..5): q, qd, qdd[, q''', q'''']");
  // Exact (dual numbers through the pin tree, the limit torques included): differences in time
  // lose digits where the motion is violent (a bounce off a joint's stop: q''' ~ 1e4 rad/s^3).
  Jet full = Jet::Zero(numJoints(), 5);
  full.leftCols(q_jet.cols()) = q_jet;
  TorqueJet out;
  out.tau = model_->pinTree().torqueJet(full);
  return out;
}

}  // namespace flatsos::planner
