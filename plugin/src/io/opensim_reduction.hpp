#pragma once
// The importer's view of an OpenSim model (opensim_import.cpp): which coordinates are kept and
// held, the reference posture, which flatsos body each OpenSim body belongs to; and the wording
// of the importer's errors.

#include <sstream>
#include <string>

#include "flatsos/plugin/io/opensim_import.hpp"
#include "flatsos/plugin/io/opensim_kinematics.hpp"

namespace flatsos::plugin::opensim_import {

inline constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;

inline std::string fixed(double x, int digits) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(digits);
  out << x;
  return out.str();
}

// A coordinate's value as people read it: degrees for rotations, metres for translations.
inline std::string shown(const OpenSimCoordinate& c, double value) {
  return c.rotational ? fixed(value * kDegPerRad, 3) + " deg" : fixed(value, 4) + " m";
}

[[noreturn]] inline void fail(const std::string& what) { throw OpenSimModelError(what); }

// The OpenSim model at its reference posture: kept coordinates at 0, the others held.
// Construction checks the kept and held coordinates and ranges.
class Reduction {
 public:
  Reduction(const OpenSimModel& osim, const OpenSimImportOptions& options);

  bool kept(const std::string& coordinate) const;
  const OpenSimCoordinateValues& reference() const { return reference_; }
  // The reference posture with one kept coordinate moved (and what is coupled to it).
  OpenSimCoordinateValues moved(const std::string& coordinate, double value) const;
  // The flatsos body an OpenSim body belongs to: itself when a kept coordinate moves it, the
  // body of the kept coordinate it is coupled to, otherwise its parent's (ground: welded).
  std::string owner(const std::string& body) const;
  // The coupler through which the body's own joint follows a kept coordinate of another joint.
  const OpenSimCoupler* coupledToKept(const std::string& body) const;

 private:
  void followCouplers(OpenSimCoordinateValues& q, const std::string& name) const;
  void checkKeptAndHeld() const;

  const OpenSimModel& osim_;
  const OpenSimImportOptions& options_;
  OpenSimCoordinateValues reference_;
};

}  // namespace flatsos::plugin::opensim_import
