#include "flatsos/plugin/force/hill_muscle.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>

#include "flatsos/muscles/hill_laws.hpp"

namespace flatsos::plugin {

namespace fm = flatsos::muscles;
using SignalPtr = std::shared_ptr<const ExcitationSignal>;

// The implementation owns parameters and path (topology); the states live in the State.
// Indices are allocated in realizeTopology and kept in mutable members, as Simbody's own force
// elements do; the force subsystem is referred to by its index, never by a copied handle.
class HillMuscleImpl : public SimTK::Force::Custom::Implementation {
 public:
  HillMuscleImpl(SimTK::SubsystemIndex forces, fm::MuscleParameters p, MusclePath path)
      : forces_(forces), p_(std::move(p)), path_(std::move(path)) {
    for (int k = 0; k < path_.length_m.dimension(); ++k) gradient_.push_back(path_.length_m.derivative(k));
  }

  const fm::MuscleParameters& parameters() const { return p_; }
  const MusclePath& path() const { return path_; }

  // ---- topology ----
  void realizeTopology(SimTK::State& s) const override {
    SimTK::Vector z_init(2);
    z_init[0] = p_.tendon_slack_length_m;
    z_init[1] = kDefaultActivation;
    first_z_ = s.allocateZ(forces_, z_init);
    held_excitation_ = s.allocateDiscreteVariable(
        forces_, SimTK::Stage::Dynamics,
        new SimTK::Value<ExcitationPolynomial>(ExcitationPolynomial::constant(kDefaultActivation)));
    signal_ = s.allocateDiscreteVariable(forces_, SimTK::Stage::Dynamics,
                                         new SimTK::Value<SignalPtr>(SignalPtr()));
  }

  // The arguments' coordinates in their matter subsystem's q and u, known from Stage::Model on.
  // MobilizedBody::getOneQ finds them through the subsystem's model cache on every call (a
  // dynamic_cast each), which took 6 % of a closed loop of the arm. Every State of a system has
  // the same layout here (the muscles' mobilizers have one coordinate each, and no State of the
  // project switches a ball or free joint to Euler angles), so they are found once, by the first
  // State asked, under a lock (a getter may be the first to ask, from any thread).
  void requireSlots(const SimTK::State& s) const {
    if (slots_ready_.load(std::memory_order_acquire)) return;
    const std::lock_guard<std::mutex> lock(slots_mutex_);
    if (slots_ready_.load(std::memory_order_relaxed)) return;
    slots_.assign(path_.arguments.size(), ArgumentSlot());
    for (std::size_t k = 0; k < path_.arguments.size(); ++k) {
      const SimTK::MobilizedBody& mobilizer = path_.arguments[k].mobilizer;
      if (mobilizer.isEmptyHandle()) continue;  // held at its value
      slots_[k].matter = mobilizer.getMatterSubsystem().getMySubsystemIndex();
      slots_[k].q = static_cast<int>(mobilizer.getFirstQIndex(s));
      slots_[k].u = static_cast<int>(mobilizer.getFirstUIndex(s));
    }
    slots_ready_.store(true, std::memory_order_release);
  }

  // ---- state access ----
  double tendonLength(const SimTK::State& s) const { return s.getZ(forces_)[first_z_]; }
  double activation(const SimTK::State& s) const { return s.getZ(forces_)[first_z_ + 1]; }
  void setZ(SimTK::State& s, int which, double v) const { s.updZ(forces_)[first_z_ + which] = v; }

  void setHeldExcitation(SimTK::State& s, const ExcitationPolynomial& piece) const {
    SimTK::Value<ExcitationPolynomial>::updDowncast(s.updDiscreteVariable(forces_, held_excitation_)) = piece;
    setSignal(s, SignalPtr());
  }
  void setSignal(SimTK::State& s, SignalPtr signal) const {
    SimTK::Value<SignalPtr>::updDowncast(s.updDiscreteVariable(forces_, signal_)) = std::move(signal);
  }
  ExcitationInput input(const SimTK::State& s) const {
    return {static_cast<const SimTK::Value<ExcitationPolynomial>&>(s.getDiscreteVariable(forces_, held_excitation_)).get(),
            static_cast<const SimTK::Value<SignalPtr>&>(s.getDiscreteVariable(forces_, signal_)).get()};
  }
  void setInput(SimTK::State& s, const ExcitationInput& input) const {
    SimTK::Value<ExcitationPolynomial>::updDowncast(s.updDiscreteVariable(forces_, held_excitation_)) = input.piece;
    setSignal(s, input.signal);
  }
  double unclampedExcitation(const SimTK::State& s) const {
    // static_cast: both variables were allocated with these types in realizeTopology, and
    // Value<T>::downcast's dynamic_cast measured ~10 % of an integration step.
    const SignalPtr& signal =
        static_cast<const SimTK::Value<SignalPtr>&>(s.getDiscreteVariable(forces_, signal_)).get();
    if (signal) return signal->value(s.getTime());
    return static_cast<const SimTK::Value<ExcitationPolynomial>&>(s.getDiscreteVariable(forces_, held_excitation_))
        .get()
        .value(s.getTime());
  }
  double excitation(const SimTK::State& s) const {
    const double n = unclampedExcitation(s);
    // NaN from a faulty signal becomes 0 (no drive) rather than poisoning the integration.
    return std::isnan(n) ? 0.0 : std::clamp(n, 0.0, 1.0);
  }

  // ---- kinematics of the path ----
  // The polynomial's arguments at the state (held ones at their values); allocation-free.
  void arguments(const SimTK::State& s, double* x) const {
    requireSlots(s);
    for (std::size_t k = 0; k < path_.arguments.size(); ++k) {
      const ArgumentSlot& slot = slots_[k];
      x[k] = slot.matter.isValid() ? s.getQ(slot.matter)[slot.q] : path_.arguments[k].held_value_rad;
    }
  }
  double length(const SimTK::State& s) const {
    double x[fm::LengthPolynomial::kMaxDimension];
    arguments(s, x);
    return path_.geometry ? path_.geometry->length_m(x) : path_.length_m.value(x);
  }
  // Moment arms about every argument (held ones 0): the geometry's, or -dL/dx of the polynomial.
  void momentArms(const SimTK::State& s, double* arms) const {
    double x[fm::LengthPolynomial::kMaxDimension];
    arguments(s, x);
    if (path_.geometry) path_.geometry->momentArms(x, arms);
    for (std::size_t k = 0; k < path_.arguments.size(); ++k) {
      if (path_.arguments[k].mobilizer.isEmptyHandle()) arms[k] = 0.0;
      else if (!path_.geometry) arms[k] = -gradient_[k].value(x);
    }
  }
  double momentArm(const SimTK::State& s, int k) const {
    double arms[fm::LengthPolynomial::kMaxDimension];
    momentArms(s, arms);
    return arms[k];
  }
  // dL/dt: the length's own rate (the tendon length is L minus the fibre's share along it).
  double lengtheningRate(const SimTK::State& s) const {
    double x[fm::LengthPolynomial::kMaxDimension], gradient[fm::LengthPolynomial::kMaxDimension];
    arguments(s, x);
    if (path_.geometry) path_.geometry->lengthGradient(x, gradient);
    double ldot = 0.0;  // arguments() has made the slots
    for (std::size_t k = 0; k < path_.arguments.size(); ++k)
      if (!path_.arguments[k].mobilizer.isEmptyHandle())
        ldot += (path_.geometry ? gradient[k] : gradient_[k].value(x)) * s.getU(slots_[k].matter)[slots_[k].u];
    return ldot;
  }

  double tendonLengthDerivative(const SimTK::State& s) const {
    return fm::tendon_length_derivative(p_, tendonLength(s), activation(s), length(s),
                                        lengtheningRate(s));
  }
  double activationDerivative(const SimTK::State& s) const {
    return fm::activation_derivative(p_, excitation(s), activation(s));
  }

  int tendonLengthYIndex(const SimTK::State& s) const {
    return static_cast<int>(s.getZStart()) + static_cast<int>(s.getZStart(forces_)) + first_z_;
  }
  fm::TendonLengthDerivativePartials tendonLengthDerivativePartials(const SimTK::State& s) const {
    return fm::tendon_length_derivative_partials(p_, tendonLength(s), activation(s), length(s));
  }
  double activationDerivativePartial(const SimTK::State& s) const {
    return fm::activation_derivative_d_activation(p_, excitation(s), activation(s));
  }

  // ---- Force::Custom::Implementation ----
  void calcForce(const SimTK::State& s, SimTK::Vector_<SimTK::SpatialVec>&,
                 SimTK::Vector_<SimTK::Vec3>&, SimTK::Vector& mobility_forces) const override {
    const double f = fm::tendon_force(p_, tendonLength(s));
    double arms[fm::LengthPolynomial::kMaxDimension];
    momentArms(s, arms);  // makes the slots
    // As MobilizedBody::applyOneMobilityForce does, from the slots (the force vector is the
    // matter subsystem's mobilities).
    for (std::size_t k = 0; k < path_.arguments.size(); ++k)
      if (slots_[k].matter.isValid()) mobility_forces[slots_[k].u] += arms[k] * f;
  }
  // The tendon stores energy, but the muscle-tendon unit is dissipative and its states are
  // first-order: no potential energy is reported to the multibody system.
  SimTK::Real calcPotentialEnergy(const SimTK::State&) const override { return 0.0; }

  void realizeAcceleration(const SimTK::State& s) const override {
    SimTK::Vector& zdot = s.updZDot(forces_);
    zdot[first_z_] = tendonLengthDerivative(s);
    zdot[first_z_ + 1] = activationDerivative(s);
  }

  static constexpr double kDefaultActivation = 0.05;

 private:
  SimTK::SubsystemIndex forces_;
  fm::MuscleParameters p_;
  MusclePath path_;
  std::vector<fm::LengthPolynomial> gradient_;  // dL/dx_k per argument
  struct ArgumentSlot {
    SimTK::SubsystemIndex matter;  // invalid: a held argument
    int q = 0, u = 0;
  };
  mutable std::vector<ArgumentSlot> slots_;  // requireSlots
  mutable std::mutex slots_mutex_;
  mutable std::atomic<bool> slots_ready_{false};
  mutable SimTK::ZIndex first_z_;
  mutable SimTK::DiscreteVariableIndex held_excitation_;
  mutable SimTK::DiscreteVariableIndex signal_;
};

namespace {
HillMuscleImpl* make_impl(SimTK::GeneralForceSubsystem& forces, const fm::MuscleParameters& p,
                          MusclePath path) {
  fm::validate(p);
  if (static_cast<int>(path.arguments.size()) != path.length_m.dimension())
    throw std::invalid_argument("muscle '" + p.name + "': the path has " + std::to_string(path.arguments.size()) +
                                " arguments for a length polynomial of dimension " +
                                std::to_string(path.length_m.dimension()));
  for (std::size_t k = 0; k < path.arguments.size(); ++k) {
    const PathArgument& arg = path.arguments[k];
    if (arg.mobilizer.isEmptyHandle() && !std::isfinite(arg.held_value_rad))
      throw std::invalid_argument("muscle '" + p.name + "': path argument " + std::to_string(k) + " is held at a value that is not finite");
  }
  return new HillMuscleImpl(forces.getMySubsystemIndex(), p, std::move(path));
}
}  // namespace

MusclePath MusclePath::constantMomentArms(double length_at_zero_angles_m, const std::vector<MomentArm>& moment_arms) {
  for (const auto& arm : moment_arms) {
    if (!std::isfinite(arm.moment_arm_m)) throw std::invalid_argument("muscle path: a moment arm is not finite");
    if (arm.mobilizer.isEmptyHandle()) throw std::invalid_argument("muscle path: a moment arm has no mobilizer");
  }
  if (!std::isfinite(length_at_zero_angles_m))
    throw std::invalid_argument("muscle path: length_at_zero_angles_m is not finite");
  // Order 1 in OpenSim's order: the constant, then the last argument's term, ..., the first's.
  MusclePath path;
  std::vector<double> c{length_at_zero_angles_m};
  for (auto it = moment_arms.rbegin(); it != moment_arms.rend(); ++it) c.push_back(-it->moment_arm_m);
  path.length_m = fm::LengthPolynomial(static_cast<int>(moment_arms.size()), 1, std::move(c));
  for (const auto& arm : moment_arms) path.arguments.push_back({arm.mobilizer, 0.0});
  return path;
}

HillMuscle::HillMuscle(SimTK::GeneralForceSubsystem& forces, const fm::MuscleParameters& parameters,
                       MusclePath path)
    : SimTK::Force::Custom(forces, make_impl(forces, parameters, std::move(path))) {}

const HillMuscleImpl& HillMuscle::impl() const {
  return static_cast<const HillMuscleImpl&>(getImplementation());
}

const fm::MuscleParameters& HillMuscle::getParameters() const { return impl().parameters(); }
const MusclePath& HillMuscle::getPath() const { return impl().path(); }

double HillMuscle::getActivation(const SimTK::State& s) const { return impl().activation(s); }
void HillMuscle::setActivation(SimTK::State& s, double activation) const {
  if (!(activation >= 0.0 && activation <= 1.0))  // also rejects NaN
    throw std::invalid_argument("muscle '" + getParameters().name + "': activation " +
                                std::to_string(activation) + " is outside [0, 1]");
  impl().setZ(s, 1, activation);
}
double HillMuscle::getTendonLength(const SimTK::State& s) const { return impl().tendonLength(s); }
void HillMuscle::setTendonLength(SimTK::State& s, double tendon_length_m) const {
  if (!(std::isfinite(tendon_length_m) && tendon_length_m > 0.0))
    throw std::invalid_argument("muscle '" + getParameters().name + "': tendon length " +
                                std::to_string(tendon_length_m) + " m is not a finite length > 0");
  impl().setZ(s, 0, tendon_length_m);
}

void HillMuscle::setExcitation(SimTK::State& s, double excitation) const {
  if (std::isnan(excitation))
    throw std::invalid_argument("muscle '" + getParameters().name + "': excitation is NaN");
  impl().setHeldExcitation(s, ExcitationPolynomial::constant(excitation));
}
void HillMuscle::setExcitationPolynomial(SimTK::State& s, const ExcitationPolynomial& piece) const {
  try {
    piece.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("muscle '" + getParameters().name + "': " + e.what());
  }
  impl().setHeldExcitation(s, piece);
}
void HillMuscle::setExcitationSignal(SimTK::State& s, std::shared_ptr<const ExcitationSignal> signal) const {
  impl().setSignal(s, std::move(signal));
}
ExcitationInput HillMuscle::getExcitationInput(const SimTK::State& s) const { return impl().input(s); }
void HillMuscle::setExcitationInput(SimTK::State& s, const ExcitationInput& input) const {
  impl().setInput(s, input);
}
double HillMuscle::getExcitation(const SimTK::State& s) const { return impl().excitation(s); }
double HillMuscle::getUnclampedExcitation(const SimTK::State& s) const {
  return impl().unclampedExcitation(s);
}

double HillMuscle::getMomentArm(const SimTK::State& s, int argument) const {
  if (argument < 0 || argument >= static_cast<int>(getPath().arguments.size()))
    throw std::out_of_range("muscle '" + getParameters().name + "': no path argument " + std::to_string(argument));
  return impl().momentArm(s, argument);
}
double HillMuscle::getMusculotendonLength(const SimTK::State& s) const { return impl().length(s); }
double HillMuscle::getMusculotendonLengtheningRate(const SimTK::State& s) const {
  return impl().lengtheningRate(s);
}
double HillMuscle::getFiberLength(const SimTK::State& s) const {
  return fm::fiber_geometry(getParameters(), impl().length(s) - impl().tendonLength(s)).length_m;
}
double HillMuscle::getTendonForce(const SimTK::State& s) const {
  return fm::tendon_force(getParameters(), impl().tendonLength(s));
}
double HillMuscle::getFiberShorteningVelocity(const SimTK::State& s) const {
  return fm::fiber_shortening_velocity(getParameters(), getTendonForce(s), getActivation(s),
                                       impl().length(s) - impl().tendonLength(s));
}
double HillMuscle::getTendonLengthDerivative(const SimTK::State& s) const {
  return impl().tendonLengthDerivative(s);
}
double HillMuscle::getActivationDerivative(const SimTK::State& s) const {
  return impl().activationDerivative(s);
}

}  // namespace flatsos::plugin

namespace flatsos::plugin {
int HillMuscle::getTendonLengthYIndex(const SimTK::State& s) const { return impl().tendonLengthYIndex(s); }
fm::TendonLengthDerivativePartials HillMuscle::getTendonLengthDerivativePartials(const SimTK::State& s) const {
  return impl().tendonLengthDerivativePartials(s);
}
double HillMuscle::getActivationDerivativePartial(const SimTK::State& s) const {
  return impl().activationDerivativePartial(s);
}
}  // namespace flatsos::plugin
