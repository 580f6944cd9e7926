#include "bindings.hpp"

#include <string>
#include <utility>
#include <vector>

#include "flatsos/plugin/io/model_file.hpp"

namespace py = pybind11;

namespace flatsos::python {

namespace {
Model with_flat_outputs(std::shared_ptr<const plugin::MusculoskeletalModel> model) {
  Model out;
  out.model = std::move(model);
  out.flat = std::make_shared<const planner::FlatOutputMap>(out.model);
  return out;
}

Model load(const std::string& path) {
  py::gil_scoped_release release;  // the flat-output choice may take a second
  return with_flat_outputs(plugin::MusculoskeletalModel::fromFile(path));
}

Model from_json(const std::string& text, const std::string& source) {
  py::gil_scoped_release release;
  return with_flat_outputs(std::make_shared<const plugin::MusculoskeletalModel>(plugin::parse_model_json(text, source)));
}
// The model with each muscle's maximum isometric force multiplied by its factor (the same flat
// outputs: E does not depend on strength, and the library's choice need not run again).
Model with_strength(const Model& self, const py::object& factors) {
  const Eigen::VectorXd f = vector_argument(factors, self.model->numMuscles(), "factors", true);
  if (!(f.array() > 0.0).all() || !f.allFinite()) throw py::value_error("factors: must be positive numbers");
  plugin::ModelDescription description = self.model->description();
  for (int j = 0; j < description.numMuscles(); ++j) description.muscles[j].parameters.max_isometric_force_N *= f[j];
  Model out;
  py::gil_scoped_release release;
  out.model = std::make_shared<const plugin::MusculoskeletalModel>(std::move(description));
  out.flat = std::make_shared<const planner::FlatOutputMap>(out.model, self.flat->E());
  return out;
}

}  // namespace

void register_model(py::module_& m) {
  py::class_<Model>(m, "Model", "A flatsos model file (JSON): its joints, muscles and flat-output map.")
      .def(py::init(&load), py::arg("path"),
           "Loads the model file; a bad file, or flat outputs that violate Assumption 1, raise ValueError.")
      .def_static("from_json", &from_json, py::arg("text"), py::arg("source") = "model",
                  "The model of a model file's JSON text (what to_json gives; `source` names it in messages).")
      .def("to_json", [](const Model& self) { return plugin::model_json_text(self.model->description()); },
           "The model as a model file's JSON text (from_json and Model(path) read it back to the same model).")
      .def_property_readonly(
          "name", [](const Model& self) { return self.model->description().name; })
      .def_property_readonly(
          "joints",
          [](const Model& self) {
            std::vector<std::string> names;
            for (const auto& j : self.model->description().joints) names.push_back(j.name);
            return names;
          },
          "joint names, in model order")
      .def_property_readonly(
          "muscles",
          [](const Model& self) {
            std::vector<std::string> names;
            for (const auto& mu : self.model->description().muscles) names.push_back(mu.parameters.name);
            return names;
          },
          "muscle names, in model order")
      .def_property_readonly(
          "flat_outputs", [](const Model& self) { return self.flat->numFlatOutputs(); }, "number of flat outputs")
      .def_property_readonly(
          "max_isometric_forces",
          [](const Model& self) {
            Eigen::VectorXd f(self.model->numMuscles());
            for (int j = 0; j < self.model->numMuscles(); ++j) f[j] = self.model->muscle(j).getParameters().max_isometric_force_N;
            return f;
          },
          "each muscle's maximum isometric force, N (model order)")
      .def("with_strength", &with_strength, py::arg("factors"),
           "A copy with each muscle's maximum isometric force multiplied by its factor (one number for all, or one "
           "per muscle; positive), with the same flat outputs. Bad factors raise ValueError.")
      .def("__repr__", [](const Model& self) {
        return "<flatsos.Model '" + self.model->description().name + "': " + std::to_string(self.model->numJoints()) +
               " joints, " + std::to_string(self.model->numMuscles()) + " muscles>";
      });
}

}  // namespace flatsos::python
