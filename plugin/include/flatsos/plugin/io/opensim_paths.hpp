#pragma once
// OpenSim's fitted muscle paths: a FunctionBasedPathSet file (what OpenSim's PolynomialPathFitter
// writes, OpenSim 4.5+), each muscle's length a MultivariatePolynomialFunction of the coordinates
// listed in its coordinate_paths. The coefficients keep OpenSim's order (ascending powers
// starting from the last coordinate), which muscles::LengthPolynomial reads unchanged. Read with
// Simbody's own XML parser (SimTK::Xml): nothing beyond Simbody.

#include <stdexcept>
#include <string>
#include <vector>

namespace flatsos::plugin {

/// A file OpenSim wrote that cannot be read as one: the message names the file and the element.
class OpenSimFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One muscle's fitted length, as the file gives it.
struct OpenSimPolynomialPath {
  std::string force_path;                     ///< e.g. "/forceset/vasint_r"
  std::string muscle;                         ///< the last component: "vasint_r"
  std::vector<std::string> coordinate_paths;  ///< e.g. "/jointset/walker_knee_r/knee_angle_r"
  std::vector<std::string> coordinates;       ///< their last components: "knee_angle_r"
  int order = 0;
  std::vector<double> coefficients;           ///< OpenSim's order; termCount(dimension, order) of them
};

/// Reads every FunctionBasedPath of a FunctionBasedPathSet document (file order). Throws
/// OpenSimFileError naming the file and the muscle for: a missing or unreadable file, a document
/// that is not a FunctionBasedPathSet, a path without a MultivariatePolynomialFunction length, a
/// dimension that differs from the number of coordinate paths, a coefficient count that does
/// not match dimension and order, a non-finite or unparsable coefficient, a muscle given twice.
std::vector<OpenSimPolynomialPath> read_opensim_function_based_paths(const std::string& file);
/// The same from the document's text; `source` names it in errors.
std::vector<OpenSimPolynomialPath> parse_opensim_function_based_paths(const std::string& xml, const std::string& source);

}  // namespace flatsos::plugin
