#include "flatsos/plugin/io/opensim_paths.hpp"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Simbody: see there

#include <SimTKcommon.h>

#include "flatsos/muscles/length_polynomial.hpp"
#include "opensim_text.hpp"

namespace flatsos::plugin {

namespace {

using opensim_text::last_component;
using opensim_text::words;

OpenSimPolynomialPath read_path(SimTK::Xml::Element& element, const std::string& source) {
  OpenSimPolynomialPath path;
  path.force_path = element.getOptionalAttributeValue("name", "");
  const std::string where = "'" + source + "': FunctionBasedPath '" + path.force_path + "'";
  if (path.force_path.empty()) throw OpenSimFileError("'" + source + "': a FunctionBasedPath without a name");
  path.muscle = last_component(path.force_path);
  if (!element.hasElement("coordinate_paths")) throw OpenSimFileError(where + ": no coordinate_paths");
  path.coordinate_paths = words(element.getRequiredElementValue("coordinate_paths"));
  for (const auto& c : path.coordinate_paths) path.coordinates.push_back(last_component(c));
  SimTK::Xml::Element length = element.getOptionalElement("length_function");
  if (!length.isValid() || !length.hasElement("MultivariatePolynomialFunction"))
    throw OpenSimFileError(where + ".length_function: not a MultivariatePolynomialFunction");
  SimTK::Xml::Element polynomial = length.getRequiredElement("MultivariatePolynomialFunction");
  auto integer = [&](const char* tag) {
    const std::vector<std::string> w = words(polynomial.getOptionalElementValue(tag, ""));
    std::size_t used = 0;
    int value = -1;
    try {
      if (w.size() == 1) value = std::stoi(w[0], &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (w.size() != 1 || used != w[0].size() || value < 0)
      throw OpenSimFileError(where + ".length_function." + tag + ": must be one integer >= 0");
    return value;
  };
  const int dimension = integer("dimension");
  path.order = integer("order");
  if (dimension != static_cast<int>(path.coordinate_paths.size()))
    throw OpenSimFileError(where + ": dimension " + std::to_string(dimension) + " but " +
                           std::to_string(path.coordinate_paths.size()) + " coordinate_paths");
  if (dimension > muscles::LengthPolynomial::kMaxDimension)
    throw OpenSimFileError(where + ": " + std::to_string(dimension) + " coordinates, more than " +
                           std::to_string(muscles::LengthPolynomial::kMaxDimension));
  for (const std::string& w : words(polynomial.getOptionalElementValue("coefficients", ""))) {
    const std::optional<double> value = opensim_text::finite_number(w);
    if (!value) throw OpenSimFileError(where + ".length_function.coefficients: '" + w + "' is not a finite number");
    path.coefficients.push_back(*value);
  }
  const long expected = muscles::LengthPolynomial::termCount(dimension, path.order);
  if (static_cast<long>(path.coefficients.size()) != expected)
    throw OpenSimFileError(where + ".length_function.coefficients: " + std::to_string(path.coefficients.size()) +
                           " given, dimension " + std::to_string(dimension) + " and order " + std::to_string(path.order) +
                           " need " + std::to_string(expected));
  return path;
}

}  // namespace

std::vector<OpenSimPolynomialPath> parse_opensim_function_based_paths(const std::string& xml, const std::string& source) {
  SimTK::Xml::Document document;
  try {
    document.readFromString(xml);
  } catch (const std::exception& e) {
    throw OpenSimFileError("'" + source + "': not an XML document (" + std::string(e.what()) + ")");
  }
  SimTK::Xml::Element root = document.getRootElement();
  SimTK::Xml::Element set = root.getElementTag() == "Set_FunctionBasedPath_" ? root : root.getOptionalElement("Set_FunctionBasedPath_");
  if (!set.isValid() || !set.hasElement("objects"))
    throw OpenSimFileError("'" + source + "': not a FunctionBasedPathSet (no Set_FunctionBasedPath_/objects)");
  SimTK::Xml::Element objects = set.getRequiredElement("objects");
  std::vector<OpenSimPolynomialPath> paths;
  std::set<std::string> seen;
  for (auto it = objects.element_begin("FunctionBasedPath"); it != objects.element_end(); ++it) {
    paths.push_back(read_path(*it, source));
    if (!seen.insert(paths.back().muscle).second)
      throw OpenSimFileError("'" + source + "': muscle '" + paths.back().muscle + "' has two FunctionBasedPaths");
  }
  if (paths.empty()) throw OpenSimFileError("'" + source + "': no FunctionBasedPath in the set");
  return paths;
}

std::vector<OpenSimPolynomialPath> read_opensim_function_based_paths(const std::string& file) {
  const std::optional<std::string> text = opensim_text::file_text(file);
  if (!text) throw OpenSimFileError("'" + file + "': cannot open the FunctionBasedPathSet file");
  return parse_opensim_function_based_paths(*text, file);
}

}  // namespace flatsos::plugin
