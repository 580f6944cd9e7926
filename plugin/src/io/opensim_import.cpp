#include "flatsos/plugin/io/opensim_import.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <set>
#include <utility>

#include <nlohmann/json.hpp>

#include "flatsos/muscles/length_polynomial.hpp"
#include "flatsos/plugin/io/opensim_kinematics.hpp"
#include "flatsos/plugin/model/posture_grid.hpp"
#include "opensim_muscle_models.hpp"
#include "opensim_reduction.hpp"
#include "opensim_slider.hpp"

namespace flatsos::plugin {

namespace {

using nlohmann::json;
using opensim_import::fail;
using opensim_import::fixed;
using opensim_import::kDegPerRad;
using opensim_import::Reduction;

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
// A pin whose body follows OpenSim's joint this closely over the range is exact (rounding only).
constexpr double kExactPinTolerance_m = 1e-9;

// The point in the plane through `joint_origin` normal to the pin's axis about which the bodies' origins and mass centres
// (those that move with the joint, not through a coupler), turned by the pin, come closest (least squares over the range) to where OpenSim's
// joint puts them: c_true(q) - R(q) c0 = (I - R(q)) p is linear in p.
// The origins and mass centres of the bodies that move with a kept joint (not those that follow
// it through a coupler, which move on their own paths), in ground.
std::vector<Eigen::Vector3d> points_moving_with_joint(const OpenSimModel& osim, const Reduction& reduction,
                                                      const std::vector<std::string>& bodies, const OpenSimCoordinateValues& q) {
  std::vector<Eigen::Vector3d> out;
  for (const std::string& b : bodies) {
    if (reduction.coupledToKept(b)) continue;
    const Eigen::Isometry3d X = opensim_body_in_ground(osim, b, q);
    out.push_back(X.translation());
    out.push_back(X * osim.body(b)->mass_center_m);
  }
  return out;
}

Eigen::Vector3d fitted_center(const OpenSimModel& osim, const Reduction& reduction, const std::vector<std::string>& bodies,
                              const std::string& coordinate, const JointDescription& pin, const Eigen::Vector3d& joint_origin) {
  auto points = [&](const OpenSimCoordinateValues& q) { return points_moving_with_joint(osim, reduction, bodies, q); };
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

// The farthest any of those points is, over the range, from where the pin puts it: 0 to
// rounding when OpenSim's joint is one rotation about the pin's axis.
double pin_point_error_m(const OpenSimModel& osim, const Reduction& reduction, const std::vector<std::string>& bodies,
                         const std::string& coordinate, const JointDescription& pin, const Eigen::Vector3d& center) {
  const std::vector<Eigen::Vector3d> at_reference = points_moving_with_joint(osim, reduction, bodies, reduction.reference());
  double worst_m = 0.0;
  for (int s = 0; s <= kRangeSamples; ++s) {
    const double q = pin.range_rad[0] + (pin.range_rad[1] - pin.range_rad[0]) * s / kRangeSamples;
    const Eigen::Matrix3d R = Eigen::AngleAxisd(q, pin.axis).toRotationMatrix();
    const std::vector<Eigen::Vector3d> truth = points_moving_with_joint(osim, reduction, bodies, reduction.moved(coordinate, q));
    for (std::size_t i = 0; i < truth.size(); ++i)
      worst_m = std::max(worst_m, (truth[i] - (center + R * (at_reference[i] - center))).norm());
  }
  return worst_m;
}

json range_deg(const std::array<double, 2>& r) { return json::array({r[0] * kDegPerRad, r[1] * kDegPerRad}); }

struct KeptJoint {
  std::string coordinate;
  const OpenSimJoint* joint;
  std::size_t depth;  // joints between it and ground
};

// One import, step by step: each step adds its part of the model, the notes and the provenance.
class Importer {
 public:
  Importer(const OpenSimModel& osim, const std::vector<OpenSimPolynomialPath>& paths, const OpenSimImportOptions& options)
      : osim_(osim), paths_(paths), options_(options), reduction_(osim, options) {}

  OpenSimImport run() {
    startProvenance();
    orderKeptJoints();
    groupBodies();
    for (const KeptJoint& k : kept_) addPin(k);
    for (const KeptJoint& k : kept_) {
      const Lumped lumped = addBody(k);
      recordMassCenterError(k, lumped);
      noteCoupledBodies(k);
    }
    addMuscles();
    dropSlackMuscles();
    if (model_.muscles.empty()) fail("no muscle's fitted length depends on the kept coordinates (or every one is slack)");
    finishProvenance();
    try {
      validate(model_, model_.name);
    } catch (const ModelFileError& e) {
      fail(std::string("the imported model is not valid: ") + e.what());
    }
    return std::move(out_);
  }

 private:
  void startProvenance() {
    model_.name = options_.name.empty() ? osim_.name : options_.name;
    model_.gravity_m_per_s2 = osim_.gravity_m_per_s2;
    provenance_ = {{"generator", "opensim_to_model (flatsos)"},
                   {"sources", {{"osim", options_.osim_source}}},
                   {"opensim_model", osim_.name}};
    if (options_.path_fit_json.empty()) {
      provenance_["sources"]["function_based_paths"] = options_.paths_source;
    } else {
      provenance_["sources"]["paths"] = "the osim's GeometryPaths, fitted";
      provenance_["path_fit"] = json::parse(options_.path_fit_json);
    }
    if (!osim_.credits.empty()) provenance_["opensim_credits"] = osim_.credits;
  }

  // Parents first.
  void orderKeptJoints() {
    for (const std::string& k : options_.keep) {
      const OpenSimJoint* joint = osim_.joint(osim_.coordinate(k)->joint);
      std::size_t depth = 0;
      for (const OpenSimJoint* j = joint; j && j->parent_body != "ground"; j = osim_.jointOfChild(j->parent_body)) ++depth;
      kept_.push_back({k, joint, depth});
    }
    std::stable_sort(kept_.begin(), kept_.end(), [](const KeptJoint& a, const KeptJoint& b) { return a.depth < b.depth; });
  }

  // Bodies: each kept joint's child with everything that moves with it.
  void groupBodies() {
    for (const auto& b : osim_.bodies) {
      const std::string owner = reduction_.owner(b.name);
      (owner == "ground" ? welded_ : members_[owner]).push_back(b.name);
    }
  }

  // A pin about the rotation the kept coordinate turns fastest at the reference posture (in 3-D:
  // OpenSim's axis as it is), through the point about which the child's bodies best follow
  // OpenSim's joint over the range (least squares). A joint whose motion is that one rotation
  // (a PinJoint, or a CustomJoint with one rotation of the coordinate) is then reproduced
  // exactly: the point is on its axis and every body follows it to rounding.
  void addPin(const KeptJoint& k) {
    if (!osim_.coordinate(k.coordinate)->rotational) return addSlider(k);
    const OpenSimCoordinateValues& q0 = reduction_.reference();
    const OpenSimJoint& j = *k.joint;
    const Eigen::Isometry3d X_GF = opensim_body_in_ground(osim_, j.parent_body, q0) * j.parent_offset;
    const Eigen::Isometry3d X_GM = X_GF * opensim_joint_transform(j, q0);
    const Eigen::Vector3d axis = X_GF.linear() * opensim_joint_rate(j, q0, k.coordinate).dominant_axis;
    if (!(axis.norm() > 0.5)) fail("kept coordinate '" + k.coordinate + "': joint '" + j.name + "' does not rotate with it");
    JointDescription d;
    d.name = j.name;
    d.coordinate = k.coordinate;
    d.parent = reduction_.owner(j.parent_body);
    d.child = j.child_body;
    // Every flatsos body frame is parallel to ground at the reference posture, so an axis in
    // ground is the axis in the parent's frame.
    d.axis = axis.normalized();
    d.range_rad = osim_.coordinate(k.coordinate)->range;
    if (const auto r = options_.ranges.find(k.coordinate); r != options_.ranges.end()) d.range_rad = r->second;
    const Eigen::Vector3d center = fitted_center(osim_, reduction_, members_.at(d.child), k.coordinate, d, X_GM.translation());
    d.location_in_parent_m = center - origin_.at(d.parent);
    origin_[d.child] = center;
    model_.joints.push_back(d);
    const double joint_error_m = pin_point_error_m(osim_, reduction_, members_.at(d.child), k.coordinate, d, center);
    pins_[j.name] = {{"coordinate", k.coordinate},
                     {"opensim_joint_type", j.type},
                     {"exact", joint_error_m <= kExactPinTolerance_m},
                     {"joint_point_error_m", joint_error_m},
                     {"axis_in_ground", {d.axis[0], d.axis[1], d.axis[2]}},
                     {"center_shift_from_joint_frame_m", (center - X_GM.translation()).norm()},
                     {"range_deg", range_deg(d.range_rad)}};
  }

  void addSlider(const KeptJoint& k) {  // a kept translation (opensim_slider.hpp)
    const auto s = opensim_import::import_slider(osim_, reduction_, options_, *k.joint, k.coordinate, origin_, members_.at(k.joint->child_body));
    origin_[s.joint.child] = s.child_origin_in_ground, sliders_[k.joint->name] = s.provenance;
    model_.joints.push_back(s.joint);
  }

  // The kept joint's child with the mass properties of everything lumped into it.
  Lumped addBody(const KeptJoint& k) {
    const OpenSimCoordinateValues& q0 = reduction_.reference();
    const std::string& name = k.joint->child_body;
    const Lumped l = lump(osim_, members_.at(name), q0);
    if (!(l.mass_kg > 0.0)) fail("body '" + name + "': no mass (with what is lumped into it)");
    BodyDescription b;
    b.name = name;
    b.mass_kg = l.mass_kg;
    b.mass_center_m = l.mass_center - origin_.at(name);
    b.principal_inertia_kg_m2 = l.inertia.diagonal();
    b.product_inertia_kg_m2 = Eigen::Vector3d(l.inertia(0, 1), l.inertia(0, 2), l.inertia(1, 2));
    // Drawn from its pin to the next pin on it, else to the farthest lumped body's origin.
    for (const auto& d : model_.joints)
      if (d.parent == name) b.length_m = std::max(b.length_m, d.location_in_parent_m.norm());
    if (b.length_m == 0.0)
      for (const std::string& m : members_.at(name))
        b.length_m = std::max(b.length_m, (opensim_body_in_ground(osim_, m, q0).translation() - origin_.at(name)).norm());
    if (b.length_m == 0.0) b.length_m = 2.0 * b.mass_center_m.norm();
    model_.bodies.push_back(b);
    return l;
  }

  // How far the pin puts its body's mass centre from where OpenSim's joint does over the range:
  // what the dynamics sees of an inexact pin and of bodies lumped where they are at the reference.
  void recordMassCenterError(const KeptJoint& k, const Lumped& lumped) {
    const std::string& name = k.joint->child_body;
    const JointDescription& d = *std::find_if(model_.joints.begin(), model_.joints.end(), [&](const auto& j) { return j.child == name; });
    double worst_m = 0.0, worst_at_rad = 0.0;
    for (int s = 0; s <= kRangeSamples; ++s) {
      const double q = d.range_rad[0] + (d.range_rad[1] - d.range_rad[0]) * s / kRangeSamples;
      const Eigen::Vector3d truth = lump(osim_, members_.at(name), reduction_.moved(k.coordinate, q)).mass_center;
      const Eigen::Vector3d by_pin = opensim_import::placed_by_joint(d, q, origin_.at(name), lumped.mass_center);
      const double error_m = (truth - by_pin).norm();
      if (error_m > worst_m) worst_m = error_m, worst_at_rad = q;
    }
    json& pin = (d.isSlider() ? sliders_ : pins_)[k.joint->name];
    pin["mass_center_error_m"] = worst_m;
    pin[d.isSlider() ? "mass_center_error_at_m" : "mass_center_error_at_deg"] = worst_at_rad * d.displayPerSI();
    std::vector<std::string> others;
    for (const std::string& m : members_.at(name))
      if (m != name) others.push_back(m);
    if (!others.empty()) pin["lumped_bodies"] = others;
    if (worst_m > kExactPinTolerance_m)
      out_.notes.push_back(joint_type_name(d.type) + (" '" + k.joint->name) + "' (" + k.joint->type + "): " + name +
                           "'s mass centre is up to " + fixed(worst_m * 1e3, 1) + " mm (at " +
                           fixed(worst_at_rad * d.displayPerSI(), d.isSlider() ? 4 : 1) + " " + d.displayUnit() +
                           ") from where OpenSim's joint puts it");
  }

  void noteCoupledBodies(const KeptJoint& k) {
    const std::string& name = k.joint->child_body;
    for (const std::string& m : members_.at(name))
      if (const OpenSimCoupler* coupler = reduction_.coupledToKept(m))
        out_.notes.push_back("body '" + m + "' follows '" + coupler->independent + "' through '" + coupler->name +
                             "': lumped into '" + name + "' where it is at the reference posture");
  }

  // Muscles: every one whose fitted length depends on a kept coordinate.
  void addMuscles() {
    std::map<std::string, const OpenSimPolynomialPath*> path_of;
    for (const auto& p : paths_) path_of[p.muscle] = &p;
    for (const auto& m : osim_.muscles) {
      std::set<std::string> owners;
      for (const std::string& b : m.path_bodies)
        if (b == "ground" || osim_.body(b)) owners.insert(reduction_.owner(b));
      const auto found = path_of.find(m.name);
      if (found == path_of.end()) {
        if (owners.size() > 1)
          fail("muscle '" + m.name + "': its path runs across a kept joint (bodies " + m.path_bodies.front() + " .. " +
               m.path_bodies.back() + ") but the paths file has no fitted path for it");
        continue;
      }
      if (const std::optional<PolynomialPathDescription> path = pathOverKept(m, *found->second))
        model_.muscles.push_back(muscleOf(m, *path));
    }
  }

  // The muscle's fitted path with the held coordinates inserted, when its length depends on a
  // kept coordinate.
  std::optional<PolynomialPathDescription> pathOverKept(const OpenSimMuscle& m, const OpenSimPolynomialPath& path) {
    PolynomialPathDescription d;
    d.coordinates = path.coordinates;
    d.order = path.order;
    d.coefficients = path.coefficients;
    std::vector<int> kept_arguments;
    for (std::size_t a = 0; a < path.coordinates.size(); ++a) {
      const std::string& c = path.coordinates[a];
      if (!osim_.coordinate(c)) fail("muscle '" + m.name + "': its fitted path uses coordinate '" + c + "', which the OpenSim model lacks");
      if (reduction_.kept(c)) {
        kept_arguments.push_back(static_cast<int>(a));
      } else {
        const OpenSimCoupler* coupler = osim_.couplerOf(c);
        if (coupler && !options_.hold.count(c) && reduction_.kept(coupler->independent))
          fail("muscle '" + m.name + "': its fitted path uses '" + c + "', which follows kept '" + coupler->independent + "'");
        d.held_coordinates_rad[c] = reduction_.reference().at(c);
      }
    }
    if (kept_arguments.empty() || !dependsOnKept(d, kept_arguments)) return std::nullopt;
    return d;
  }

  // True when some partial derivative over a kept argument is not identically 0 once the held
  // values are in (a polynomial that is not 0 is not 0 at random points).
  bool dependsOnKept(const PolynomialPathDescription& d, const std::vector<int>& kept_arguments) {
    const muscles::LengthPolynomial polynomial(static_cast<int>(d.coordinates.size()), d.order, d.coefficients);
    bool depends = false;
    std::vector<double> x(d.coordinates.size());
    for (int trial = 0; trial < 8 && !depends; ++trial) {
      for (std::size_t a = 0; a < x.size(); ++a) {
        const auto held = d.held_coordinates_rad.find(d.coordinates[a]);
        if (held != d.held_coordinates_rad.end()) {
          x[a] = held->second;
        } else {
          const auto& joint = *std::find_if(model_.joints.begin(), model_.joints.end(),
                                            [&](const auto& j) { return j.coordinate == d.coordinates[a]; });
          x[a] = std::uniform_real_distribution<double>(joint.range_rad[0], joint.range_rad[1])(rng_);
        }
      }
      for (int a : kept_arguments) depends = depends || polynomial.derivative(a).value(x.data()) != 0.0;
    }
    return depends;
  }

  MuscleDescription muscleOf(const OpenSimMuscle& m, const PolynomialPathDescription& path) {
    MuscleDescription md;
    md.parameters = opensim_import::muscle_parameters_of(m, out_.notes, opensim_import::muscle_model_choice(options_));
    md.polynomial_path = path;
    return md;
  }

  // Slack tendons: the fitted length must exceed the tendon slack length over the whole range.
  void dropSlackMuscles() {
    for (std::size_t j = 0; j < model_.muscles.size();) {
      const muscles::MusculotendonPath path = model_.musclePath(static_cast<int>(j));
      const muscles::MuscleParameters& p = model_.muscles[j].parameters;
      double shortest_m = std::numeric_limits<double>::infinity();
      Eigen::VectorXd where;
      json arms = json::object();
      std::vector<std::array<double, 2>> arm_range(model_.joints.size(), {INFINITY, -INFINITY});
      Eigen::VectorXd arm(model_.numJoints());
      for_each_posture(model_, path.crossedJoints(), options_.slack_check_postures, [&](const Eigen::VectorXd& q) {
        const double length = path.length(q.data());
        if (length < shortest_m) shortest_m = length, where = q;
        path.momentArms(q.data(), arm.data());
        for (int i : path.crossedJoints())
          arm_range[i] = {std::min(arm_range[i][0], arm[i]), std::max(arm_range[i][1], arm[i])};
      });
      for (int i : path.crossedJoints())
        arms[model_.joints[i].coordinate] = json::array({arm_range[i][0] * 1e3, arm_range[i][1] * 1e3});
      if (shortest_m > p.tendon_slack_length_m) {
        moment_arms_[p.name] = arms;
        ++j;
        continue;
      }
      const std::string why = "its fitted length " + fixed(shortest_m, 4) + " m at " +
                              describe_posture(model_, path.crossedJoints(), where) + " does not exceed its tendon slack length " +
                              fixed(p.tendon_slack_length_m, 4) + " m: the tendon cannot be taut there";
      if (options_.refuse_slack_muscles) fail("muscle '" + p.name + "': " + why);
      out_.notes.push_back("muscle '" + p.name + "' left out: " + why);
      left_out_.push_back({{"muscle", p.name}, {"reason", why}});
      model_.muscles.erase(model_.muscles.begin() + static_cast<std::ptrdiff_t>(j));
    }
  }

  void finishProvenance() {
    json held = json::object();
    for (const auto& c : osim_.coordinates)
      if (!reduction_.kept(c.name) && reduction_.reference().at(c.name) != 0.0)
        held[c.name] = c.rotational ? reduction_.reference().at(c.name) * kDegPerRad : reduction_.reference().at(c.name);
    provenance_["kept_coordinates"] = options_.keep;
    provenance_["held_coordinates"] = {{"values_deg_or_m", held}, {"every_other_coordinate", 0.0}};
    provenance_["welded_to_ground"] = welded_;
    provenance_["pins"] = pins_;
    if (!sliders_.empty()) provenance_["sliders"] = sliders_;
    provenance_["approximations"] = {
        "each kept coordinate is a pin about the axis it turns fastest at the reference posture (kept coordinates 0), "
        "through the point its bodies best turn about: exact for a joint that is one rotation (pins.*.exact, "
        "pins.*.joint_point_error_m); a CustomJoint's other motions with that coordinate (the walker knee's translations and small rotations) are "
        "dropped, and pins.*.mass_center_error_m measures the effect",
        "bodies that follow a kept coordinate through a coupler are lumped where they are at the reference posture",
        opensim_import::muscle_approximation(options_.millard_with_flatsos_laws),
        options_.path_fit_json.empty()
            ? "muscle lengths: OpenSim's fitted polynomials (FunctionBasedPath) with held coordinates inserted, trusted only "
              "inside the ranges where they were fitted"
            : "muscle lengths: polynomials of the kept coordinates fitted to the GeometryPaths (via points, wrapping) over the "
              "kept ranges with the other coordinates held, as OpenSim's PolynomialPathFitter fits; path_fit gives each "
              "muscle's length and moment-arm errors (m) between the fitting samples"};
    if (options_.opensim_2_muscles) provenance_["opensim_2_muscles"] = "Thelen2003Muscle as OpenSim 2.x modelled it";
    if (options_.degroote_fregly2016_muscles)
      provenance_["degroote_fregly2016_muscles"] = opensim_import::degroote_replacement(options_.ignore_passive_fiber_forces);
    provenance_["left_out_muscles"] = left_out_;
    provenance_["moment_arm_ranges_mm"] = moment_arms_;
    provenance_["notes"] = out_.notes;
    model_.provenance_json = provenance_.dump();
  }

  const OpenSimModel& osim_;
  const std::vector<OpenSimPolynomialPath>& paths_;
  const OpenSimImportOptions& options_;
  const Reduction reduction_;  // first: it checks the options
  OpenSimImport out_;
  ModelDescription& model_ = out_.model;
  json provenance_;
  std::vector<KeptJoint> kept_;  // parents first
  std::map<std::string, std::vector<std::string>> members_;  // flatsos body -> OpenSim bodies
  std::vector<std::string> welded_;
  std::map<std::string, Eigen::Vector3d> origin_ = {{"ground", Eigen::Vector3d::Zero()}};  // flatsos body -> its pin's point in ground
  json pins_ = json::object(), sliders_ = json::object();
  json left_out_ = json::array(), moment_arms_ = json::object();
  std::mt19937_64 rng_{20261124};
};

}  // namespace

OpenSimImport import_opensim_model(const OpenSimModel& osim, const std::vector<OpenSimPolynomialPath>& paths,
                                   const OpenSimImportOptions& options) {
  return Importer(osim, paths, options).run();
}

}  // namespace flatsos::plugin
