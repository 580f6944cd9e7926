#include "osim_xml.hpp"

#include <stdexcept>

#include "../io/opensim_text.hpp"
#include "flatsos/plugin/io/opensim_paths.hpp"  // OpenSimFileError

namespace flatsos::plugin::osim_xml {

void Reader::fail(const std::string& where, const std::string& what) const {
  throw OpenSimFileError("'" + source_ + "': " + where + ": " + what);
}

std::vector<double> Reader::numbers(Element& e, const char* tag, const std::string& where, std::size_t count) const {
  const std::string at = where + "." + tag;
  if (!e.hasElement(tag)) fail(at, "missing");
  std::vector<double> out;
  for (const std::string& w : opensim_text::words(e.getRequiredElementValue(tag))) {
    const std::optional<double> value = opensim_text::finite_number(w);
    if (!value) fail(at, "'" + w + "' is not a finite number");
    out.push_back(*value);
  }
  if (count && out.size() != count) fail(at, "needs " + std::to_string(count) + " numbers, got " + std::to_string(out.size()));
  return out;
}

double Reader::number_or(Element& e, const char* tag, const std::string& where, double fallback) const {
  return e.hasElement(tag) ? numbers(e, tag, where, 1)[0] : fallback;
}

Eigen::Vector3d Reader::vec3_or(Element& e, const char* tag, const std::string& where, const Eigen::Vector3d& fallback) const {
  if (!e.hasElement(tag)) return fallback;
  const std::vector<double> v = numbers(e, tag, where, 3);
  return {v[0], v[1], v[2]};
}

bool Reader::bool_or(Element& e, const char* tag, const std::string& where, bool fallback) const {
  if (!e.hasElement(tag)) return fallback;
  const std::string value = text(e, tag);
  if (value == "true" || value == "1") return true;
  if (value == "false" || value == "0") return false;
  fail(where + "." + tag, "'" + value + "' is not true or false");
}

std::string Reader::text(Element& e, const char* tag) const {
  const std::vector<std::string> w = opensim_text::words(e.getOptionalElementValue(tag, ""));
  std::string out;
  for (const std::string& part : w) out += (out.empty() ? "" : " ") + part;
  return out;
}

OpenSimFunction Reader::function(Element& container, const std::string& where, const OpenSimFunction& fallback) const {
  for (auto it = container.element_begin(); it != container.element_end(); ++it) {
    Element f = *it;
    const std::string tag = f.getElementTag();
    const std::string at = where + "." + tag;
    if (tag == "function") return function(f, at, fallback);
    if (tag == "Constant") return OpenSimFunction::constant(numbers(f, "value", at, 1)[0]);
    if (tag == "LinearFunction") {
      const std::vector<double> c = numbers(f, "coefficients", at, 2);
      return OpenSimFunction::linear(c[0], c[1]);
    }
    if (tag == "PolynomialFunction") {
      const std::vector<double> c = numbers(f, "coefficients", at, 0);
      if (c.empty()) fail(at + ".coefficients", "no coefficients");
      return OpenSimFunction::polynomial(c);
    }
    if (tag == "SimmSpline") {
      try {
        return OpenSimFunction::simmSpline(numbers(f, "x", at, 0), numbers(f, "y", at, 0));
      } catch (const std::invalid_argument& e) {
        fail(at, e.what());
      }
    }
    if (tag == "MultiplierFunction") {
      if (!f.hasElement("function")) fail(at, "missing <function>");
      Element inner = f.getRequiredElement("function");
      const OpenSimFunction none = OpenSimFunction::unsupported("(none)");
      const OpenSimFunction scaled = function(inner, at + ".function", none);
      if (scaled.typeName() == "(none)") fail(at + ".function", "holds no function");
      return scaled.scaled(number_or(f, "scale", at, 1.0));
    }
    if (!f.getOptionalAttributeValue("name", "").empty() || tag.find("Function") != std::string::npos ||
        tag.find("Spline") != std::string::npos)
      return OpenSimFunction::unsupported(tag);
  }
  return fallback;
}

Element find_below(Element& e, const std::string& tag) {
  for (auto it = e.element_begin(); it != e.element_end(); ++it) {
    Element child = *it;
    if (child.getElementTag() == tag) return child;
    Element found = find_below(child, tag);
    if (found.isValid()) return found;
  }
  return Element();
}

Element set_objects(Element& owner, const char* set) {
  Element s = owner.getOptionalElement(set);
  return s.isValid() ? s.getOptionalElement("objects") : Element();
}

Eigen::Matrix3d body_fixed_xyz(const Eigen::Vector3d& angles) {
  return (Eigen::AngleAxisd(angles[0], Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(angles[1], Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(angles[2], Eigen::Vector3d::UnitZ()))
      .toRotationMatrix();
}

}  // namespace flatsos::plugin::osim_xml
