// Python arguments into the library's types, and the library's tables out as numpy arrays.
#include "bindings.hpp"

#include <string>
#include <vector>

#include "flatsos/plugin/io/state_table.hpp"

namespace py = pybind11;

namespace flatsos::python {

std::shared_ptr<const planner::Effort> effort_argument(const py::handle& effort, const py::handle& weights,
                                                       Eigen::Index muscles) {
  if (!effort.is_none() && !py::isinstance<py::str>(effort))
    throw py::value_error("effort: expected None, 'paper' or a name such as 'excitation_squared'");
  const std::string name = effort.is_none() ? "paper" : py::cast<std::string>(effort);
  if (name == "paper") {
    if (!weights.is_none()) throw py::value_error("weights: the 'paper' effort weighs the muscles by the model's effort_weights");
    return nullptr;
  }
  const Eigen::VectorXd w = weights.is_none() ? Eigen::VectorXd() : vector_argument(weights, muscles, "weights", true);
  return planner::effort_named(name, w);  // std::invalid_argument (ValueError) naming the known efforts
}

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

std::optional<Eigen::VectorXd> activations_argument(const py::handle& a0, Eigen::Index muscles) {
  if (a0.is_none()) return std::nullopt;
  Eigen::VectorXd a = vector_argument(a0, muscles, "a0");
  if (!((a.array() > 0.0).all() && (a.array() <= 1.0).all())) throw py::value_error("a0: activations must lie in (0, 1]");
  return a;
}

Eigen::VectorXd column_vector(const plugin::StoTable& table, const std::string& label) {
  const std::vector<double> c = table.column(label);
  return Eigen::Map<const Eigen::VectorXd>(c.data(), static_cast<Eigen::Index>(c.size()));
}

Table columns_table(const plugin::StoTable& table, const std::vector<std::string>& labels) {
  Table out(static_cast<Eigen::Index>(table.rows.size()), static_cast<Eigen::Index>(labels.size()));
  for (std::size_t k = 0; k < labels.size(); ++k) out.col(static_cast<Eigen::Index>(k)) = column_vector(table, labels[k]);
  return out;
}

std::vector<std::string> joint_value_columns(const plugin::MusculoskeletalModel& model) {
  std::vector<std::string> labels;
  for (int i = 0; i < model.numJoints(); ++i) labels.push_back(plugin::coordinate_value_column(model, i));
  return labels;
}

std::vector<std::string> muscle_columns(const plugin::MusculoskeletalModel& model, const std::string& suffix) {
  std::vector<std::string> labels;
  for (int j = 0; j < model.numMuscles(); ++j)
    labels.push_back("/forceset/" + model.muscle(j).getParameters().name + suffix);
  return labels;
}

}  // namespace flatsos::python
