#include "flatsos/plugin/io/opensim_import.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "flatsos/muscles/length_polynomial.hpp"
#include "flatsos/plugin/io/opensim_kinematics.hpp"
#include "flatsos/plugin/model/posture_grid.hpp"

namespace flatsos::plugin {

namespace {

using nlohmann::json;
constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;
constexpr double kMaxAxisTiltRad = 45.0 / kDegPerRad;

std::string fixed(double x, int digits) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(digits);
  out << x;
  return out.str();
}

// A coordinate's value as people read it: degrees for rotations, metres for translations.
std::string shown(const OpenSimCoordinate& c, double value) {
  return c.rotational ? fixed(value * kDegPerRad, 3) + " deg" : fixed(value, 4) + " m";
}

[[noreturn]] void fail(const std::string& what) { throw OpenSimModelError(what); }

// The importer's view of the OpenSim model at its reference posture: kept coordinates at 0,
// the others held.
class Reduction {
 public:
  Reduction(const OpenSimModel& osim, const OpenSimImportOptions& options) : osim_(osim), options_(options) {
    checkKeptAndHeld();
    for (const auto& c : osim_.coordinates) {
      const auto held = options_.hold.find(c.name);
      reference_[c.name] = held == options_.hold.end() ? 0.0 : held->second;
    }
    for (const auto& c : osim_.coordinates) followCouplers(reference_, c.name);
  }

  bool kept(const std::string& coordinate) const {
    return std::find(options_.keep.begin(), options_.keep.end(), coordinate) != options_.keep.end();
  }
  const OpenSimCoordinateValues& reference() const { return reference_; }

  // The reference posture with one kept coordinate moved (and what is coupled to it).
  OpenSimCoordinateValues moved(const std::string& coordinate, double value) const {
    OpenSimCoordinateValues q = reference_;
    q[coordinate] = value;
    for (const auto& c : osim_.coordinates) followCouplers(q, c.name);
    return q;
  }

  // The flatsos body an OpenSim body belongs to: itself when a kept coordinate moves it, the
  // body of the kept coordinate it is coupled to, otherwise its parent's (ground: welded).
  std::string owner(const std::string& body) const {
    if (body == "ground") return body;
    const OpenSimJoint* joint = osim_.jointOfChild(body);
    if (!joint) fail("body '" + body + "' is not connected to ground by joints");
    for (const std::string& c : joint->coordinates) {
      if (kept(c)) return body;
      const OpenSimCoupler* coupler = osim_.couplerOf(c);
      if (coupler && !options_.hold.count(c) && kept(coupler->independent))
        return owner(osim_.joint(osim_.coordinate(coupler->independent)->joint)->child_body);
    }
    return owner(joint->parent_body);
  }
  // True when the body's own joint is coupled to a kept coordinate of another joint.
  const OpenSimCoupler* coupledToKept(const std::string& body) const {
    const OpenSimJoint* joint = osim_.jointOfChild(body);
    if (!joint) return nullptr;
    for (const std::string& c : joint->coordinates) {
      const OpenSimCoupler* coupler = osim_.couplerOf(c);
      if (coupler && !options_.hold.count(c) && kept(coupler->independent)) return coupler;
    }
    return nullptr;
  }

 private:
  void followCouplers(OpenSimCoordinateValues& q, const std::string& name) const {
    const OpenSimCoupler* coupler = osim_.couplerOf(name);
    if (!coupler || options_.hold.count(name)) return;
    try {
      q[name] = coupler->scale * coupler->function.value(q.at(coupler->independent));
    } catch (const std::runtime_error& e) {
      fail("CoordinateCouplerConstraint '" + coupler->name + "': " + e.what());
    }
  }

  void checkKeptAndHeld() const {
    if (options_.keep.empty()) fail("no coordinate to keep: name at least one (--keep)");
    std::set<std::string> kept_joints, seen;
    for (const std::string& k : options_.keep) {
      const OpenSimCoordinate* c = osim_.coordinate(k);
      if (!c) fail("kept coordinate '" + k + "': the OpenSim model has no such coordinate");
      if (!seen.insert(k).second) fail("kept coordinate '" + k + "': given twice");
      if (options_.hold.count(k)) fail("coordinate '" + k + "': both kept and held");
      if (!c->rotational) fail("kept coordinate '" + k + "': a translation (only rotations become pin joints)");
      if (const OpenSimCoupler* coupler = osim_.couplerOf(k))
        fail("kept coordinate '" + k + "': it follows '" + coupler->independent + "' (CoordinateCouplerConstraint '" +
             coupler->name + "'); keep '" + coupler->independent + "' instead");
      if (!kept_joints.insert(c->joint).second)
        fail("kept coordinate '" + k + "': another kept coordinate belongs to joint '" + c->joint +
             "' (one pin per joint: keep one of them)");
      if (!options_.ranges.count(k) && !(std::isfinite(c->range[0]) && std::isfinite(c->range[1])))
        fail("kept coordinate '" + k + "': the OpenSim model gives it no finite range; give one (--range)");
      if (const auto range = options_.ranges.find(k); range != options_.ranges.end()) {
        const auto& [lo, hi] = range->second;
        if (!(lo < hi) || lo < c->range[0] - 1e-12 || hi > c->range[1] + 1e-12)
          fail("range of '" + k + "': [" + shown(*c, lo) + ", " + shown(*c, hi) + "] is not an interval inside the coordinate's range [" +
               shown(*c, c->range[0]) + ", " + shown(*c, c->range[1]) + "]");
      }
    }
    for (const auto& [name, _] : options_.ranges)
      if (!seen.count(name)) fail("range of '" + name + "': not a kept coordinate");
    for (const auto& [name, value] : options_.hold) {
      const OpenSimCoordinate* c = osim_.coordinate(name);
      if (!c) fail("held coordinate '" + name + "': the OpenSim model has no such coordinate");
      if (!std::isfinite(value) || value < c->range[0] - 1e-12 || value > c->range[1] + 1e-12)
        fail("held coordinate '" + name + "': " + shown(*c, value) + " is outside its range [" + shown(*c, c->range[0]) + ", " +
             shown(*c, c->range[1]) + "]");
    }
  }

  const OpenSimModel& osim_;
  const OpenSimImportOptions& options_;
  OpenSimCoordinateValues reference_;
};

struct Lumped {
  double mass_kg = 0.0;
  Eigen::Vector3d mass_center = Eigen::Vector3d::Zero();  // ground
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();      // about mass_center, ground axes
};

// Mass properties of bodies at their poses combined (parallel-axis theorem).
Lumped lump(const OpenSimModel& osim, const std::vector<std::string>& bodies, const OpenSimCoordinateValues& q) {
  Lumped out;
  std::vector<std::pair<Eigen::Isometry3d, const OpenSimBody*>> placed;
  for (const std::string& name : bodies) {
    placed.emplace_back(opensim_body_in_ground(osim, name, q), osim.body(name));
    out.mass_kg += placed.back().second->mass_kg;
    out.mass_center += placed.back().second->mass_kg * (placed.back().first * placed.back().second->mass_center_m);
  }
  if (out.mass_kg > 0.0) out.mass_center /= out.mass_kg;
  for (const auto& [X, b] : placed) {
    const Eigen::Vector3d d = X * b->mass_center_m - out.mass_center;
    out.inertia += X.linear() * b->inertia_kg_m2 * X.linear().transpose() +
                   b->mass_kg * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  }
  return out;
}

constexpr int kRangeSamples = 60;

// The point in the plane through `joint_origin` about which the bodies' origins and mass centres
// (those that move with the joint, not through a coupler), turned by the pin, come closest (least squares over the range) to where OpenSim's
// joint puts them: c_true(q) - R(q) c0 = (I - R(q)) p is linear in p.
Eigen::Vector3d fitted_center(const OpenSimModel& osim, const Reduction& reduction, const std::vector<std::string>& bodies,
                              const std::string& coordinate, const JointDescription& pin, const Eigen::Vector3d& joint_origin) {
  auto points = [&](const OpenSimCoordinateValues& q) {
    std::vector<Eigen::Vector3d> out;
    for (const std::string& b : bodies) {
      if (reduction.coupledToKept(b)) continue;  // moves on its own path, not with the joint
      const Eigen::Isometry3d X = opensim_body_in_ground(osim, b, q);
      out.push_back(X.translation());
      out.push_back(X * osim.body(b)->mass_center_m);
    }
    return out;
  };
  const std::vector<Eigen::Vector3d> at_reference = points(reduction.reference());
  const Eigen::Vector3d u = pin.axis.unitOrthogonal(), v = pin.axis.cross(u);
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (int s = 0; s <= kRangeSamples; ++s) {
    const double q = pin.range_rad[0] + (pin.range_rad[1] - pin.range_rad[0]) * s / kRangeSamples;
    const Eigen::Matrix3d R = Eigen::AngleAxisd(q, pin.axis).toRotationMatrix();
    Eigen::Matrix<double, 3, 2> M;
    M << (Eigen::Matrix3d::Identity() - R) * u, (Eigen::Matrix3d::Identity() - R) * v;
    const std::vector<Eigen::Vector3d> truth = points(reduction.moved(coordinate, q));
    for (std::size_t i = 0; i < truth.size(); ++i) {
      const Eigen::Vector3d r = truth[i] - R * at_reference[i] - (Eigen::Matrix3d::Identity() - R) * joint_origin;
      A += M.transpose() * M;
      b += M.transpose() * r;
    }
  }
  // A is singular only when the range has no width; then the joint's own origin is the answer.
  const Eigen::Vector2d x = A.determinant() > 1e-12 ? Eigen::Vector2d(A.ldlt().solve(b)) : Eigen::Vector2d::Zero();
  return joint_origin + x[0] * u + x[1] * v;
}

json range_deg(const std::array<double, 2>& r) { return json::array({r[0] * kDegPerRad, r[1] * kDegPerRad}); }

}  // namespace

OpenSimImport import_opensim_model(const OpenSimModel& osim, const std::vector<OpenSimPolynomialPath>& paths,
                                   const OpenSimImportOptions& options) {
  const Reduction reduction(osim, options);
  OpenSimImport out;
  ModelDescription& model = out.model;
  model.name = options.name.empty() ? osim.name : options.name;
  model.gravity_m_per_s2 = osim.gravity_m_per_s2;
  json provenance = {{"generator", "opensim_to_model (flatsos)"},
                     {"sources", {{"osim", options.osim_source}, {"function_based_paths", options.paths_source}}},
                     {"opensim_model", osim.name}};
  if (!osim.credits.empty()) provenance["opensim_credits"] = osim.credits;

  // Kept joints, parents first.
  struct Kept {
    std::string coordinate;
    const OpenSimJoint* joint;
    std::size_t depth;
  };
  std::vector<Kept> kept;
  for (const std::string& k : options.keep) {
    const OpenSimJoint* joint = osim.joint(osim.coordinate(k)->joint);
    std::size_t depth = 0;
    for (const OpenSimJoint* j = joint; j && j->parent_body != "ground"; j = osim.jointOfChild(j->parent_body)) ++depth;
    kept.push_back({k, joint, depth});
  }
  std::stable_sort(kept.begin(), kept.end(), [](const Kept& a, const Kept& b) { return a.depth < b.depth; });

  // Bodies: each kept joint's child with everything that moves with it.
  std::map<std::string, std::vector<std::string>> members;  // flatsos body -> OpenSim bodies
  std::vector<std::string> welded;
  for (const auto& b : osim.bodies) {
    const std::string owner = reduction.owner(b.name);
    (owner == "ground" ? welded : members[owner]).push_back(b.name);
  }
  const OpenSimCoordinateValues& q0 = reduction.reference();

  // Pins: about the rotation the kept coordinate turns fastest at the reference posture,
  // projected on the plane's normal (the ground axis nearest the first pin's), through the
  // point in the plane about which the child's bodies best follow OpenSim's joint over the
  // range (least squares; the joint frame's origin when the joint is a true pin).
  std::map<std::string, Eigen::Vector3d> origin;  // flatsos body -> its pin's point in ground
  origin["ground"] = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  json pins = json::object();
  for (const Kept& k : kept) {
    const OpenSimJoint& j = *k.joint;
    const Eigen::Isometry3d X_GF = opensim_body_in_ground(osim, j.parent_body, q0) * j.parent_offset;
    const Eigen::Isometry3d X_GM = X_GF * opensim_joint_transform(j, q0);
    const Eigen::Vector3d axis = X_GF.linear() * opensim_joint_rate(j, q0, k.coordinate).dominant_axis;
    if (!(axis.norm() > 0.5)) fail("kept coordinate '" + k.coordinate + "': joint '" + j.name + "' does not rotate with it");
    if (normal.isZero()) {
      Eigen::Index i = 0;
      axis.cwiseAbs().maxCoeff(&i);
      normal = Eigen::Vector3d::Unit(i);
    }
    const double along = axis.dot(normal);
    const double tilt = std::acos(std::min(1.0, std::abs(along)));
    if (tilt > kMaxAxisTiltRad)
      fail("kept coordinate '" + k.coordinate + "': its axis is " + fixed(tilt * kDegPerRad, 1) +
           " deg from the plane's normal (the importer builds planar models: keep coordinates that rotate in one plane)");
    JointDescription d;
    d.name = j.name;
    d.coordinate = k.coordinate;
    d.parent = reduction.owner(j.parent_body);
    d.child = j.child_body;
    d.axis = along > 0.0 ? normal : Eigen::Vector3d(-normal);
    const OpenSimCoordinate& c = *osim.coordinate(k.coordinate);
    d.range_rad = c.range;
    if (const auto r = options.ranges.find(k.coordinate); r != options.ranges.end()) d.range_rad = r->second;
    const Eigen::Vector3d center = fitted_center(osim, reduction, members.at(d.child), k.coordinate, d, X_GM.translation());
    d.location_in_parent_m = center - origin.at(d.parent);
    origin[d.child] = center;
    model.joints.push_back(d);
    pins[j.name] = {{"coordinate", k.coordinate},
                    {"opensim_joint_type", j.type},
                    {"axis_tilt_dropped_deg", tilt * kDegPerRad},
                    {"center_shift_from_joint_frame_m", (center - X_GM.translation()).norm()},
                    {"range_deg", range_deg(d.range_rad)}};
    if (tilt > 1e-9)
      out.notes.push_back("pin '" + j.name + "': OpenSim's axis is tilted " + fixed(tilt * kDegPerRad, 2) +
                          " deg from the plane's normal; the pin turns about the normal");
  }

  // Mass properties, and how far each pin puts its body's mass centre from where OpenSim's joint does.
  for (const Kept& k : kept) {
    const std::string& name = k.joint->child_body;
    const Lumped l = lump(osim, members.at(name), q0);
    if (!(l.mass_kg > 0.0)) fail("body '" + name + "': no mass (with what is lumped into it)");
    BodyDescription b;
    b.name = name;
    b.mass_kg = l.mass_kg;
    b.mass_center_m = l.mass_center - origin.at(name);
    b.principal_inertia_kg_m2 = l.inertia.diagonal();
    b.product_inertia_kg_m2 = Eigen::Vector3d(l.inertia(0, 1), l.inertia(0, 2), l.inertia(1, 2));
    // Drawn from its pin to the next pin on it, else to the farthest lumped body's origin.
    for (const auto& d : model.joints)
      if (d.parent == name) b.length_m = std::max(b.length_m, d.location_in_parent_m.norm());
    if (b.length_m == 0.0)
      for (const std::string& m : members.at(name))
        b.length_m = std::max(b.length_m, (opensim_body_in_ground(osim, m, q0).translation() - origin.at(name)).norm());
    if (b.length_m == 0.0) b.length_m = 2.0 * b.mass_center_m.norm();
    model.bodies.push_back(b);

    const JointDescription& d = *std::find_if(model.joints.begin(), model.joints.end(), [&](const auto& j) { return j.child == name; });
    // In the plane (what the planar model's dynamics sees) and out of it (the tilt dropped).
    double worst = 0.0, at = 0.0, worst_out = 0.0;
    for (int s = 0; s <= kRangeSamples; ++s) {
      const double q = d.range_rad[0] + (d.range_rad[1] - d.range_rad[0]) * s / kRangeSamples;
      const Eigen::Vector3d truth = lump(osim, members.at(name), reduction.moved(k.coordinate, q)).mass_center;
      const Eigen::Vector3d pin = origin.at(name) + Eigen::AngleAxisd(q, d.axis) * (l.mass_center - origin.at(name));
      const Eigen::Vector3d error = truth - pin;
      const double out_of_plane = std::abs(error.dot(d.axis)), in_plane = (error - error.dot(d.axis) * d.axis).norm();
      if (in_plane > worst) worst = in_plane, at = q;
      worst_out = std::max(worst_out, out_of_plane);
    }
    pins[k.joint->name]["mass_center_error_in_plane_m"] = worst;
    pins[k.joint->name]["mass_center_error_at_deg"] = at * kDegPerRad;
    pins[k.joint->name]["mass_center_error_out_of_plane_m"] = worst_out;
    std::vector<std::string> others;
    for (const std::string& m : members.at(name))
      if (m != name) others.push_back(m);
    if (!others.empty()) pins[k.joint->name]["lumped_bodies"] = others;
    if (worst > 1e-6 || worst_out > 1e-6)
      out.notes.push_back("pin '" + k.joint->name + "' (" + k.joint->type + "): " + name + "'s mass centre is up to " +
                          fixed(worst * 1e3, 1) + " mm in the plane (at " + fixed(at * kDegPerRad, 1) + " deg) and " +
                          fixed(worst_out * 1e3, 1) + " mm out of it from where OpenSim's joint puts it");
    for (const std::string& m : members.at(name))
      if (const OpenSimCoupler* coupler = reduction.coupledToKept(m))
        out.notes.push_back("body '" + m + "' follows '" + coupler->independent + "' through '" + coupler->name +
                            "': lumped into '" + name + "' where it is at the reference posture");
  }
  // Muscles: every one whose fitted length depends on a kept coordinate.
  std::map<std::string, const OpenSimPolynomialPath*> path_of;
  for (const auto& p : paths) path_of[p.muscle] = &p;
  std::mt19937_64 rng(20261124);
  json left_out = json::array(), moment_arms = json::object();
  for (const auto& m : osim.muscles) {
    std::set<std::string> owners;
    for (const std::string& b : m.path_bodies)
      if (b == "ground" || osim.body(b)) owners.insert(reduction.owner(b));
    const auto found = path_of.find(m.name);
    if (found == path_of.end()) {
      if (owners.size() > 1)
        fail("muscle '" + m.name + "': its path runs across a kept joint (bodies " + m.path_bodies.front() + " .. " +
             m.path_bodies.back() + ") but the paths file has no fitted path for it");
      continue;
    }
    const OpenSimPolynomialPath& path = *found->second;
    PolynomialPathDescription d;
    d.coordinates = path.coordinates;
    d.order = path.order;
    d.coefficients = path.coefficients;
    std::vector<int> kept_arguments;
    for (std::size_t a = 0; a < path.coordinates.size(); ++a) {
      const std::string& c = path.coordinates[a];
      if (!osim.coordinate(c)) fail("muscle '" + m.name + "': its fitted path uses coordinate '" + c + "', which the OpenSim model lacks");
      if (reduction.kept(c)) {
        kept_arguments.push_back(static_cast<int>(a));
      } else {
        const OpenSimCoupler* coupler = osim.couplerOf(c);
        if (coupler && !options.hold.count(c) && reduction.kept(coupler->independent))
          fail("muscle '" + m.name + "': its fitted path uses '" + c + "', which follows kept '" + coupler->independent + "'");
        d.held_coordinates_rad[c] = reduction.reference().at(c);
      }
    }
    if (kept_arguments.empty()) continue;
    // Depends on a kept coordinate when some partial derivative is not identically 0 once the
    // held values are in (a polynomial that is not 0 is not 0 at random points).
    const muscles::LengthPolynomial polynomial(static_cast<int>(d.coordinates.size()), d.order, d.coefficients);
    bool depends = false;
    std::vector<double> x(d.coordinates.size());
    for (int trial = 0; trial < 8 && !depends; ++trial) {
      for (std::size_t a = 0; a < x.size(); ++a) {
        const auto held = d.held_coordinates_rad.find(d.coordinates[a]);
        if (held != d.held_coordinates_rad.end()) {
          x[a] = held->second;
        } else {
          const auto& joint = *std::find_if(model.joints.begin(), model.joints.end(),
                                            [&](const auto& j) { return j.coordinate == d.coordinates[a]; });
          x[a] = std::uniform_real_distribution<double>(joint.range_rad[0], joint.range_rad[1])(rng);
        }
      }
      for (int a : kept_arguments) depends = depends || polynomial.derivative(a).value(x.data()) != 0.0;
    }
    if (!depends) continue;
    MuscleDescription md;
    muscles::MuscleParameters& p = md.parameters;
    p.name = m.name;
    p.max_isometric_force_N = m.max_isometric_force_N;
    p.optimal_fiber_length_m = m.optimal_fiber_length_m;
    p.tendon_slack_length_m = m.tendon_slack_length_m;
    p.pennation_angle_at_optimal_rad = m.pennation_angle_at_optimal_rad;
    p.max_shortening_velocity_in_optimal_lengths_per_s = m.max_contraction_velocity_in_optimal_lengths_per_s;
    p.activation_time_constant_s = m.activation_time_constant_s;
    p.deactivation_time_constant_s = m.deactivation_time_constant_s;
    // OpenSim's minimum activation is flatsos' activation floor: the same clamp from below, and
    // the bound every plan keeps.
    p.activation_floor = m.minimum_activation;
    p.tendon_strain_at_max_force = m.tendon_strain_at_one_norm_force;
    p.passive_fiber_strain_at_one_norm_force = m.passive_fiber_strain_at_one_norm_force;
    md.polynomial_path = d;
    model.muscles.push_back(md);
  }

  // Slack tendons: the fitted length must exceed the tendon slack length over the whole range.
  for (std::size_t j = 0; j < model.muscles.size();) {
    const muscles::MusculotendonPath path = model.musclePath(static_cast<int>(j));
    const muscles::MuscleParameters& p = model.muscles[j].parameters;
    double shortest = std::numeric_limits<double>::infinity();
    Eigen::VectorXd where;
    json arms = json::object();
    std::vector<std::array<double, 2>> arm_range(model.joints.size(), {INFINITY, -INFINITY});
    Eigen::VectorXd arm(model.numJoints());
    for_each_posture(model, path.crossedJoints(), options.slack_check_postures, [&](const Eigen::VectorXd& q) {
      const double length = path.length(q.data());
      if (length < shortest) shortest = length, where = q;
      path.momentArms(q.data(), arm.data());
      for (int i : path.crossedJoints())
        arm_range[i] = {std::min(arm_range[i][0], arm[i]), std::max(arm_range[i][1], arm[i])};
    });
    for (int i : path.crossedJoints())
      arms[model.joints[i].coordinate] = json::array({arm_range[i][0] * 1e3, arm_range[i][1] * 1e3});
    if (shortest > p.tendon_slack_length_m) {
      moment_arms[p.name] = arms;
      ++j;
      continue;
    }
    const std::string why = "its fitted length " + fixed(shortest, 4) + " m at " + describe_posture(model, path.crossedJoints(), where) +
                            " does not exceed its tendon slack length " + fixed(p.tendon_slack_length_m, 4) +
                            " m: the tendon cannot be taut there";
    if (options.refuse_slack_muscles) fail("muscle '" + p.name + "': " + why);
    out.notes.push_back("muscle '" + p.name + "' left out: " + why);
    left_out.push_back({{"muscle", p.name}, {"reason", why}});
    model.muscles.erase(model.muscles.begin() + static_cast<std::ptrdiff_t>(j));
  }
  if (model.muscles.empty()) fail("no muscle's fitted length depends on the kept coordinates (or every one is slack)");

  json held = json::object();
  for (const auto& c : osim.coordinates)
    if (!reduction.kept(c.name) && reduction.reference().at(c.name) != 0.0)
      held[c.name] = c.rotational ? reduction.reference().at(c.name) * kDegPerRad : reduction.reference().at(c.name);
  provenance["kept_coordinates"] = options.keep;
  provenance["held_coordinates"] = {{"values_deg_or_m", held}, {"every_other_coordinate", 0.0}};
  provenance["welded_to_ground"] = welded;
  provenance["pins"] = pins;
  provenance["approximations"] = {
      "each kept coordinate is a pin about the plane's normal through its joint's child frame at the reference posture "
      "(kept coordinates 0): a CustomJoint's other motions with that coordinate (the walker knee's translations and "
      "small rotations) and axis tilts out of the plane are dropped; pins.*.mass_center_error_* measure the effect",
      "bodies that follow a kept coordinate through a coupler are lumped where they are at the reference posture",
      "muscles: OpenSim's maximum isometric force, optimal fibre length, tendon slack length, pennation, maximum "
      "contraction velocity and curve strains with flatsos' Hill laws in place of the OpenSim muscle's curves",
      "muscle lengths: OpenSim's fitted polynomials (FunctionBasedPath) with held coordinates inserted, trusted only inside "
      "the ranges where they were fitted"};
  provenance["left_out_muscles"] = left_out;
  provenance["moment_arm_ranges_mm"] = moment_arms;
  provenance["notes"] = out.notes;
  model.provenance_json = provenance.dump();
  try {
    validate(model, model.name);
  } catch (const ModelFileError& e) {
    fail(std::string("the imported model is not valid: ") + e.what());
  }
  return out;
}

}  // namespace flatsos::plugin
