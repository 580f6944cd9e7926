// Python arguments into the library's types.
#include "bindings.hpp"

#include <string>
#include <vector>

namespace py = pybind11;

namespace flatsos::python {

Eigen::VectorXd vector_argument(const py::handle& x, Eigen::Index n, const std::string& name, bool broadcast) {
  const std::string expected = std::to_string(n) + (broadcast ? " numbers or one number" : " numbers");
  if (py::isinstance<py::str>(x) || x.is_none()) throw py::value_error(name + ": expected " + expected);
  std::vector<double> v;
  try {
    if (py::hasattr(x, "__len__")) v = py::cast<std::vector<double>>(x);
    else if (broadcast) v.assign(static_cast<std::size_t>(n), py::cast<double>(x));
    else throw py::value_error(name + ": expected " + expected + ", got one number");
  } catch (const py::cast_error&) {
    throw py::value_error(name + ": expected " + expected);
  }
  if (static_cast<Eigen::Index>(v.size()) != n)
    throw py::value_error(name + ": expected " + expected + ", got " + std::to_string(v.size()));
  return Eigen::Map<const Eigen::VectorXd>(v.data(), n);
}

}  // namespace flatsos::python
