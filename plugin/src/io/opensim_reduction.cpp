#include "opensim_reduction.hpp"

#include <algorithm>
#include <cmath>
#include <set>

namespace flatsos::plugin::opensim_import {

Reduction::Reduction(const OpenSimModel& osim, const OpenSimImportOptions& options) : osim_(osim), options_(options) {
  checkKeptAndHeld();
  for (const auto& c : osim_.coordinates) {
    const auto held = options_.hold.find(c.name);
    reference_[c.name] = held == options_.hold.end() ? 0.0 : held->second;
  }
  for (const auto& c : osim_.coordinates) followCouplers(reference_, c.name);
}

bool Reduction::kept(const std::string& coordinate) const {
  return std::find(options_.keep.begin(), options_.keep.end(), coordinate) != options_.keep.end();
}

OpenSimCoordinateValues Reduction::moved(const std::string& coordinate, double value) const {
  OpenSimCoordinateValues q = reference_;
  q[coordinate] = value;
  for (const auto& c : osim_.coordinates) followCouplers(q, c.name);
  return q;
}

std::string Reduction::owner(const std::string& body) const {
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

const OpenSimCoupler* Reduction::coupledToKept(const std::string& body) const {
  const OpenSimJoint* joint = osim_.jointOfChild(body);
  if (!joint) return nullptr;
  for (const std::string& c : joint->coordinates) {
    const OpenSimCoupler* coupler = osim_.couplerOf(c);
    if (coupler && !options_.hold.count(c) && kept(coupler->independent)) return coupler;
  }
  return nullptr;
}

void Reduction::followCouplers(OpenSimCoordinateValues& q, const std::string& name) const {
  const OpenSimCoupler* coupler = osim_.couplerOf(name);
  if (!coupler || options_.hold.count(name)) return;
  try {
    q[name] = coupler->scale * coupler->function.value(q.at(coupler->independent));
  } catch (const std::runtime_error& e) {
    fail("CoordinateCouplerConstraint '" + coupler->name + "': " + e.what());
  }
}

void Reduction::checkKeptAndHeld() const {
  if (options_.keep.empty()) fail("no coordinate to keep: name at least one (--keep)");
  std::set<std::string> kept_joints, seen;
  for (const std::string& k : options_.keep) {
    const OpenSimCoordinate* c = osim_.coordinate(k);
    if (!c) fail("kept coordinate '" + k + "': the OpenSim model has no such coordinate");
    if (!seen.insert(k).second) fail("kept coordinate '" + k + "': given twice");
    if (options_.hold.count(k)) fail("coordinate '" + k + "': both kept and held");
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

}  // namespace flatsos::plugin::opensim_import
