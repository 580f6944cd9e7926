#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"
#include "flatsos/plugin/model/plausibility.hpp"

#include <map>
#include <stdexcept>

#include "../integration/system_dynamics_lock.hpp"

namespace flatsos::plugin {

namespace {

SimTK::Vec3 to_vec3(const Eigen::Vector3d& v) { return SimTK::Vec3(v[0], v[1], v[2]); }

SimTK::MassProperties mass_properties(const BodyDescription& b) {
  const SimTK::Inertia about_com(to_vec3(b.principal_inertia_kg_m2), to_vec3(b.product_inertia_kg_m2));
  // Simbody wants the inertia about the body origin (the joint): shift from the mass center.
  const SimTK::Vec3 com = to_vec3(b.mass_center_m);
  return SimTK::MassProperties(b.mass_kg, com, about_com.shiftFromMassCenter(com, b.mass_kg));
}

// Pin mobilizers rotate about their frames' z axis, Slider mobilizers translate along their x
// axis: orient both frames so that axis is the joint's (the child's frame is then the parent's
// at coordinate 0).
SimTK::MobilizedBody add_mobilizer(SimTK::MobilizedBody& parent, const JointDescription& jd, const SimTK::Body::Rigid& body) {
  const SimTK::Rotation r(SimTK::UnitVec3(to_vec3(jd.axis)), SimTK::CoordinateAxis(jd.isSlider() ? 0 : 2));  // x or z
  const SimTK::Transform inboard(r, to_vec3(jd.location_in_parent_m)), outboard(r, SimTK::Vec3(0));
  if (jd.isSlider()) return SimTK::MobilizedBody::Slider(parent, inboard, body, outboard);
  return SimTK::MobilizedBody::Pin(parent, inboard, body, outboard);
}

// An external joint torque given as a function of time (disturbances, tests); a force along a
// slider.
class JointTorqueImpl : public SimTK::Force::Custom::Implementation {
 public:
  JointTorqueImpl(SimTK::MobilizedBody joint, std::shared_ptr<const ExcitationSignal> torque)
      : joint_(std::move(joint)), torque_(std::move(torque)) {}
  void calcForce(const SimTK::State& s, SimTK::Vector_<SimTK::SpatialVec>&, SimTK::Vector_<SimTK::Vec3>&,
                 SimTK::Vector& mobility_forces) const override {
    joint_.applyOneMobilityForce(s, 0, torque_->value(s.getTime()), mobility_forces);
  }
  SimTK::Real calcPotentialEnergy(const SimTK::State&) const override { return 0.0; }
  bool dependsOnlyOnPositions() const override { return false; }

 private:
  SimTK::MobilizedBody joint_;
  std::shared_ptr<const ExcitationSignal> torque_;
};

// A joint's passive limit torque (joint_limit.hpp; a force for a slider), with its spring's
// potential energy so that the system's energy accounts for it.
class JointLimitImpl : public SimTK::Force::Custom::Implementation {
 public:
  JointLimitImpl(SimTK::MobilizedBody joint, JointLimitTorque limit, std::array<double, 2> range_rad)
      : joint_(std::move(joint)), limit_(limit), range_rad_(range_rad) {}
  void calcForce(const SimTK::State& s, SimTK::Vector_<SimTK::SpatialVec>&, SimTK::Vector_<SimTK::Vec3>&,
                 SimTK::Vector& mobility_forces) const override {
    const double torque =
        joint_limit_torque(limit_, range_rad_[0], range_rad_[1], joint_.getOneQ(s, 0), joint_.getOneU(s, 0));
    if (torque != 0.0) joint_.applyOneMobilityForce(s, 0, torque, mobility_forces);
  }
  SimTK::Real calcPotentialEnergy(const SimTK::State& s) const override {
    return joint_limit_potential_energy(limit_, range_rad_[0], range_rad_[1], joint_.getOneQ(s, 0));
  }
  bool dependsOnlyOnPositions() const override { return false; }

 private:
  SimTK::MobilizedBody joint_;
  JointLimitTorque limit_;
  std::array<double, 2> range_rad_;
};

}  // namespace

ModelWorkspace::ModelWorkspace(const MusculoskeletalModel& model)
    : model_(&model), state_(model.defaultState()), tree_(model.pinTree().makeScratch()) {}

MusculoskeletalModel::MusculoskeletalModel(ModelDescription description, std::vector<ExternalJointTorque> external)
    : description_((validate(description), std::move(description))),
      warnings_(plausibility_warnings(description_)),
      matter_(system_),
      forces_(system_),
      tree_(description_) {
  for (const auto& e : external) {
    if (e.joint < 0 || e.joint >= numJoints())
      throw std::invalid_argument("external joint torque: no joint " + std::to_string(e.joint) + " (the model has " +
                                  std::to_string(numJoints()) + ")");
    if (!e.torque_N_m) throw std::invalid_argument("external joint torque on joint " + std::to_string(e.joint) + ": no torque signal");
  }
  gravity_ = SimTK::Force::Gravity(forces_, matter_, to_vec3(description_.gravity_m_per_s2));

  std::map<std::string, const BodyDescription*> bodies;
  for (const auto& b : description_.bodies) bodies[b.name] = &b;
  std::map<std::string, SimTK::MobilizedBody> built = {{"ground", matter_.Ground()}};
  for (const auto& jd : description_.joints) {
    const SimTK::MobilizedBody joint =
        add_mobilizer(built.at(jd.parent), jd, SimTK::Body::Rigid(mass_properties(*bodies.at(jd.child))));
    built[jd.child] = joint;
    joints_.push_back(joint);
  }

  if (description_.hasConstantMomentArms()) moment_arms_ = description_.momentArmMatrix();
  for (int j = 0; j < numMuscles(); ++j) {
    paths_.push_back(description_.musclePath(j));
    const muscles::MusculotendonPath& mp = paths_.back();
    MusclePath path;
    path.length_m = mp.lengthPolynomial();
    path.geometry = description_.muscles[static_cast<std::size_t>(j)].path_geometry;
    for (const muscles::PathCoordinate& c : mp.coordinates())
      path.arguments.push_back(c.held() ? PathArgument{SimTK::MobilizedBody(), c.held_value_rad}
                                        : PathArgument{joints_[static_cast<std::size_t>(c.joint)], 0.0});
    muscles_.emplace_back(forces_, description_.muscles[j].parameters, std::move(path));
  }
  for (int i = 0; i < numJoints(); ++i) {
    const JointDescription& jd = description_.joints[static_cast<std::size_t>(i)];
    if (jd.limit.enabled())
      SimTK::Force::Custom(forces_, new JointLimitImpl(joints_[static_cast<std::size_t>(i)], jd.limit, jd.range_rad));
  }
  for (auto& e : external)
    SimTK::Force::Custom(forces_, new JointTorqueImpl(joints_[static_cast<std::size_t>(e.joint)], std::move(e.torque_N_m)));
  system_.realizeTopology();
}

std::shared_ptr<const MusculoskeletalModel> MusculoskeletalModel::fromFile(const std::string& path) {
  return std::make_shared<const MusculoskeletalModel>(load_model_file(path));
}

void MusculoskeletalModel::checkWorkspace(const ModelWorkspace& ws) const {
  if (ws.model_ != this) throw std::invalid_argument("model workspace: made for another model");
}

void MusculoskeletalModel::checkSize(const Eigen::Ref<const Eigen::VectorXd>& v, int n, const char* what) const {
  if (v.size() != n)
    throw std::invalid_argument(std::string(what) + ": expected " + std::to_string(n) +
                                " values, got " + std::to_string(v.size()));
  if (!v.allFinite()) throw std::invalid_argument(std::string(what) + ": values must be finite");
}

Eigen::VectorXd MusculoskeletalModel::jointAngles(const SimTK::State& s) const {
  Eigen::VectorXd q(numJoints());
  jointAngles(s, q);
  return q;
}
Eigen::VectorXd MusculoskeletalModel::jointSpeeds(const SimTK::State& s) const {
  Eigen::VectorXd qd(numJoints());
  jointSpeeds(s, qd);
  return qd;
}
void MusculoskeletalModel::jointAngles(const SimTK::State& s, Eigen::Ref<Eigen::VectorXd> q) const {
  if (q.size() != numJoints()) throw std::invalid_argument("joint angles: the output needs one entry per joint");
  for (int i = 0; i < numJoints(); ++i) q[i] = joints_[i].getOneQ(s, 0);
}
void MusculoskeletalModel::jointSpeeds(const SimTK::State& s, Eigen::Ref<Eigen::VectorXd> qd) const {
  if (qd.size() != numJoints()) throw std::invalid_argument("joint speeds: the output needs one entry per joint");
  for (int i = 0; i < numJoints(); ++i) qd[i] = joints_[i].getOneU(s, 0);
}
void MusculoskeletalModel::setJointAngles(SimTK::State& s, const Eigen::VectorXd& q) const {
  checkSize(q, numJoints(), "joint angles");
  for (int i = 0; i < numJoints(); ++i) joints_[i].setOneQ(s, 0, q[i]);
}
void MusculoskeletalModel::setJointSpeeds(SimTK::State& s, const Eigen::VectorXd& qd) const {
  checkSize(qd, numJoints(), "joint speeds");
  for (int i = 0; i < numJoints(); ++i) joints_[i].setOneU(s, 0, qd[i]);
}

Eigen::VectorXd MusculoskeletalModel::activations(const SimTK::State& s) const {
  Eigen::VectorXd v(numMuscles());
  for (int j = 0; j < numMuscles(); ++j) v[j] = muscles_[j].getActivation(s);
  return v;
}
Eigen::VectorXd MusculoskeletalModel::tendonLengths(const SimTK::State& s) const {
  Eigen::VectorXd v(numMuscles());
  for (int j = 0; j < numMuscles(); ++j) v[j] = muscles_[j].getTendonLength(s);
  return v;
}
Eigen::VectorXd MusculoskeletalModel::tendonForces(const SimTK::State& s) const {
  Eigen::VectorXd v(numMuscles());
  for (int j = 0; j < numMuscles(); ++j) v[j] = muscles_[j].getTendonForce(s);
  return v;
}
Eigen::VectorXd MusculoskeletalModel::excitations(const SimTK::State& s) const {
  Eigen::VectorXd v(numMuscles());
  for (int j = 0; j < numMuscles(); ++j) v[j] = muscles_[j].getExcitation(s);
  return v;
}
void MusculoskeletalModel::setActivations(SimTK::State& s, const Eigen::VectorXd& a) const {
  checkSize(a, numMuscles(), "activations");
  for (int j = 0; j < numMuscles(); ++j) muscles_[j].setActivation(s, a[j]);
}
void MusculoskeletalModel::setTendonLengths(SimTK::State& s, const Eigen::VectorXd& ls) const {
  checkSize(ls, numMuscles(), "tendon lengths");
  for (int j = 0; j < numMuscles(); ++j) muscles_[j].setTendonLength(s, ls[j]);
}
void MusculoskeletalModel::setExcitations(SimTK::State& s, const Eigen::VectorXd& n) const {
  checkSize(n, numMuscles(), "excitations");
  for (int j = 0; j < numMuscles(); ++j) muscles_[j].setExcitation(s, n[j]);
}

Eigen::VectorXd MusculoskeletalModel::musculotendonLengths(const Eigen::VectorXd& q) const {
  checkSize(q, numJoints(), "joint angles");
  Eigen::VectorXd L(numMuscles());
  for (int j = 0; j < numMuscles(); ++j) L[j] = paths_[static_cast<std::size_t>(j)].length(q.data());
  return L;
}

const Eigen::MatrixXd& MusculoskeletalModel::momentArmMatrix() const {
  if (moment_arms_.size() == 0)
    throw std::logic_error("model '" + description_.name +
                           "': its moment arms depend on posture, so it has no constant moment-arm matrix (use "
                           "momentArmMatrix(q))");
  return moment_arms_;
}

Eigen::MatrixXd MusculoskeletalModel::momentArmMatrix(const Eigen::VectorXd& q) const {
  checkSize(q, numJoints(), "joint angles");
  Eigen::MatrixXd R(numJoints(), numMuscles());
  for (int j = 0; j < numMuscles(); ++j) paths_[static_cast<std::size_t>(j)].momentArms(q.data(), R.col(j).data());
  return R;
}

const muscles::MusculotendonPath& MusculoskeletalModel::musclePath(int j) const {
  if (j < 0 || j >= numMuscles())
    throw std::out_of_range("muscle path: no muscle " + std::to_string(j) + " (the model has " + std::to_string(numMuscles()) + ")");
  return paths_[static_cast<std::size_t>(j)];
}

double MusculoskeletalModel::musculotendonLength(int j, const Eigen::Ref<const Eigen::VectorXd>& q) const {
  if (j < 0 || j >= numMuscles())
    throw std::out_of_range("musculotendon length: no muscle " + std::to_string(j) + " (the model has " +
                            std::to_string(numMuscles()) + ")");
  if (q.size() != numJoints())
    throw std::invalid_argument("joint angles: expected " + std::to_string(numJoints()) + " values, got " +
                                std::to_string(q.size()));
  return paths_[static_cast<std::size_t>(j)].length(q.data());
}

Eigen::VectorXd MusculoskeletalModel::muscleTorques(const Eigen::VectorXd& f) const {
  checkSize(f, numMuscles(), "tendon forces");
  return momentArmMatrix() * f;
}

Eigen::VectorXd MusculoskeletalModel::muscleTorques(const Eigen::VectorXd& q, const Eigen::VectorXd& f) const {
  checkSize(f, numMuscles(), "tendon forces");
  return momentArmMatrix(q) * f;
}

const SimTK::State& MusculoskeletalModel::realizeVelocity(ModelWorkspace& ws, const Eigen::VectorXd& q,
                                                         const Eigen::VectorXd& qd) const {
  checkWorkspace(ws);
  setJointAngles(ws.state_, q);
  setJointSpeeds(ws.state_, qd);
  system_.realize(ws.state_, SimTK::Stage::Velocity);
  return ws.state_;
}

Eigen::MatrixXd MusculoskeletalModel::massMatrix(ModelWorkspace& ws, const Eigen::VectorXd& q) const {
  const SimTK::State& s = realizeVelocity(ws, q, Eigen::VectorXd::Zero(numJoints()));
  matter_.calcM(s, ws.mass_);
  Eigen::MatrixXd out(numJoints(), numJoints());
  for (int r = 0; r < numJoints(); ++r)
    for (int c = 0; c < numJoints(); ++c)
      out(r, c) = ws.mass_(joints_[r].getFirstUIndex(s), joints_[c].getFirstUIndex(s));
  return out;
}

Eigen::MatrixXd MusculoskeletalModel::massMatrix(const Eigen::VectorXd& q) const {
  ModelWorkspace ws(*this);
  return massMatrix(ws, q);
}

void MusculoskeletalModel::checkInverseDynamics(const ModelWorkspace& ws, const Eigen::Ref<const Eigen::VectorXd>& q,
                                                const Eigen::Ref<const Eigen::VectorXd>& qd,
                                                const Eigen::Ref<const Eigen::VectorXd>& qdd,
                                                const Eigen::Ref<Eigen::VectorXd>& tau) const {
  checkWorkspace(ws);
  checkSize(q, numJoints(), "joint angles");
  checkSize(qd, numJoints(), "joint speeds");
  checkSize(qdd, numJoints(), "joint accelerations");
  if (tau.size() != numJoints())
    throw std::invalid_argument("inverse dynamics: the torque output has " + std::to_string(tau.size()) +
                                " entries, the model " + std::to_string(numJoints()) + " joints");
}

void MusculoskeletalModel::inverseDynamics(ModelWorkspace& ws, const Eigen::Ref<const Eigen::VectorXd>& q,
                                           const Eigen::Ref<const Eigen::VectorXd>& qd,
                                           const Eigen::Ref<const Eigen::VectorXd>& qdd,
                                           Eigen::Ref<Eigen::VectorXd> tau) const {
  checkInverseDynamics(ws, q, qd, qdd, tau);
  tree_.inverseDynamics(ws.tree_, q, qd, qdd, tau);
}

void MusculoskeletalModel::rigidBodyInverseDynamics(ModelWorkspace& ws, const Eigen::Ref<const Eigen::VectorXd>& q,
                                                    const Eigen::Ref<const Eigen::VectorXd>& qd,
                                                    const Eigen::Ref<const Eigen::VectorXd>& qdd,
                                                    Eigen::Ref<Eigen::VectorXd> tau) const {
  checkInverseDynamics(ws, q, qd, qdd, tau);
  tree_.rigidBodyInverseDynamics(ws.tree_, q, qd, qdd, tau);
}

Eigen::VectorXd MusculoskeletalModel::inverseDynamics(ModelWorkspace& ws, const Eigen::VectorXd& q,
                                                      const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) const {
  Eigen::VectorXd tau(numJoints());
  inverseDynamics(ws, q, qd, qdd, tau);
  return tau;
}

Eigen::VectorXd MusculoskeletalModel::inverseDynamics(const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                                      const Eigen::VectorXd& qdd) const {
  ModelWorkspace ws(*this);
  return inverseDynamics(ws, q, qd, qdd);
}

double MusculoskeletalModel::mechanicalEnergy(const SimTK::State& s) const {
  const auto lock = detail::lock_system_dynamics(system_);
  system_.realize(s, SimTK::Stage::Dynamics);
  return system_.calcEnergy(s);
}

}  // namespace flatsos::plugin
