#pragma once
// Reading values out of an .osim document (SimTK::Xml) with errors that name the file, the
// component and the field: "'arm26.osim': TRIlong: PathPoint 'TRIlong-P2'.location: ...".

#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <SimTKcommon.h>

#include "flatsos/plugin/io/opensim_function.hpp"

namespace flatsos::plugin::osim_xml {

using Element = SimTK::Xml::Element;

class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  /// Throws OpenSimFileError "'source': where: what".
  [[noreturn]] void fail(const std::string& where, const std::string& what) const;

  /// The element's text as `count` finite numbers (any count when 0).
  std::vector<double> numbers(Element& e, const char* tag, const std::string& where, std::size_t count) const;
  double number_or(Element& e, const char* tag, const std::string& where, double fallback) const;
  Eigen::Vector3d vec3_or(Element& e, const char* tag, const std::string& where, const Eigen::Vector3d& fallback) const;
  bool bool_or(Element& e, const char* tag, const std::string& where, bool fallback) const;
  /// The element's text without surrounding blanks ("" when absent).
  std::string text(Element& e, const char* tag) const;

  /// The one function held by `container` (an <x_location>, a <function>, ...): Constant,
  /// LinearFunction, PolynomialFunction, SimmSpline, MultiplierFunction, possibly wrapped in
  /// <function> (OpenSim 3); another named function is Unsupported (evaluating it throws).
  /// `fallback` when the container holds none.
  OpenSimFunction function(Element& container, const std::string& where, const OpenSimFunction& fallback) const;

 private:
  std::string source_;
};

/// The first element of this tag anywhere below e (depth first), or an invalid element.
Element find_below(Element& e, const std::string& tag);
/// The <objects> of a set (<BodySet><objects>), or an invalid element.
Element set_objects(Element& owner, const char* set);
/// OpenSim's <orientation> / <xyz_body_rotation>: body-fixed X, then Y, then Z.
Eigen::Matrix3d body_fixed_xyz(const Eigen::Vector3d& angles);

}  // namespace flatsos::plugin::osim_xml
