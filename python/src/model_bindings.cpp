#include "bindings.hpp"

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "flatsos/planner/task_region.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"

namespace py = pybind11;

namespace flatsos::python {

std::shared_ptr<const planner::FlatOutputMap> flat_for_task(const Model& m, const std::vector<Eigen::VectorXd>& postures) {
  if (m.flat) return m.flat;
  return std::make_shared<const planner::FlatOutputMap>(planner::flat_outputs_for_task(m.model, postures));
}

namespace {
Model with_flat_outputs(std::shared_ptr<const plugin::MusculoskeletalModel> model) {
  Model out;
  out.model = std::move(model);
  try {
    out.flat = std::make_shared<const planner::FlatOutputMap>(out.model);
  } catch (const planner::FlatnessError&) {
    if (!out.model->description().flat_outputs.empty()) throw;  // the file's own E is wrong: say so now
  }
  return out;
}

// The model's plausibility warnings (unit mix-ups) as Python UserWarnings, when it is loaded:
// before any plan, whose failure must not hide them.
Model warned(Model model) {
  for (const std::string& w : model.model->warnings())
    if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 2) != 0) throw py::error_already_set();
  return model;
}

// A model file, or an OpenSim model imported with its own settings (what the programs' --model,
// --paths, --opensim-2-muscles, --degroote-muscles and --ignore-passive-fiber-forces do).
Model load(const std::string& path, const std::string& paths, bool opensim_2_muscles, bool degroote_muscles,
           bool ignore_passive_fiber_forces) {
  if (paths != "fitted" && paths != "geometry") throw py::value_error("paths: 'fitted' or 'geometry', not '" + paths + "'");
  const bool osim = plugin::is_opensim_model_file(path);
  const char* osim_only = opensim_2_muscles             ? "opensim_2_muscles"
                          : degroote_muscles            ? "degroote_muscles"
                          : ignore_passive_fiber_forces ? "ignore_passive_fiber_forces"
                          : paths == "geometry"         ? "paths='geometry'"
                                                        : nullptr;
  if (!osim && osim_only)
    throw py::value_error(std::string(osim_only) + ": the model must be an OpenSim model (.osim), not '" + path + "'");
  plugin::OpenSimFileOptions options;
  options.simulate_geometry = paths == "geometry";
  options.opensim_2_muscles = opensim_2_muscles;
  options.degroote_fregly2016_muscles = degroote_muscles;
  options.ignore_passive_fiber_forces = ignore_passive_fiber_forces;
  Model out;
  {
    py::gil_scoped_release release;  // the import and the flat-output choice may take seconds
    out = !osim ? with_flat_outputs(plugin::MusculoskeletalModel::fromFile(path))
                : with_flat_outputs(std::make_shared<const plugin::MusculoskeletalModel>(
                      plugin::import_opensim_file(path, options).model));
  }
  return warned(std::move(out));
}

Model from_json(const std::string& text, const std::string& source) {
  Model out;
  {
    py::gil_scoped_release release;
    out = with_flat_outputs(std::make_shared<const plugin::MusculoskeletalModel>(plugin::parse_model_json(text, source)));
  }
  return warned(std::move(out));
}
// The model with each muscle's maximum isometric force multiplied by its factor, with the same
// flat outputs (the library's choice, which scores moment arms, need not run again; a chosen
// one keeps its effort, tendon force over maximum force, now of the new forces).
Model with_strength(const Model& self, const py::object& factors) {
  const Eigen::VectorXd f = vector_argument(factors, self.model->numMuscles(), "factors", true);
  if (!(f.array() > 0.0).all() || !f.allFinite()) throw py::value_error("factors: must be positive numbers");
  plugin::ModelDescription description = self.model->description();
  for (int j = 0; j < description.numMuscles(); ++j) description.muscles[j].parameters.max_isometric_force_N *= f[j];
  Model out;
  py::gil_scoped_release release;
  out.model = std::make_shared<const plugin::MusculoskeletalModel>(std::move(description));
  if (self.flat) out.flat = std::make_shared<const planner::FlatOutputMap>(self.flat->withModel(out.model));
  return out;
}

// Each joint's child body in the ground frame at posture q (Simbody's kinematics): origins
// (joints x 3, m) and rotations (joints x 3 x 3, body to ground).
py::tuple body_frames(const Model& self, const py::object& q) {
  const plugin::MusculoskeletalModel& model = *self.model;
  const Eigen::VectorXd q_rad = vector_argument(q, model.numJoints(), "q");
  if (!q_rad.allFinite()) throw py::value_error("q: coordinates must be finite");
  SimTK::State s = model.defaultState();
  model.setJointAngles(s, q_rad);
  model.system().realize(s, SimTK::Stage::Position);
  const py::ssize_t n = model.numJoints();
  Table origins(n, 3);
  py::array_t<double> rotations({n, py::ssize_t{3}, py::ssize_t{3}});
  auto r = rotations.mutable_unchecked<3>();
  for (int i = 0; i < model.numJoints(); ++i) {
    const SimTK::Transform& X = model.joint(i).getBodyTransform(s);
    for (int a = 0; a < 3; ++a) {
      origins(i, a) = X.p()[a];
      for (int b = 0; b < 3; ++b) r(i, a, b) = X.R()[a][b];
    }
  }
  return py::make_tuple(origins, rotations);
}

}  // namespace

void register_model(py::module_& m) {
  py::class_<Model>(m, "Model", "A flatsos model (a JSON model file or an OpenSim .osim): its joints, muscles and flat-output map.")
      .def(py::init(&load), py::arg("path"), py::kw_only(), py::arg("paths") = "fitted",
           py::arg("opensim_2_muscles") = false, py::arg("degroote_muscles") = false,
           py::arg("ignore_passive_fiber_forces") = false,
           "Loads the model file, or imports an OpenSim model (.osim) with its own settings: paths='geometry' "
           "simulates its GeometryPaths (plans use the fitted ones), opensim_2_muscles its Thelen muscles and "
           "cylinder wrapping as OpenSim 2.x modelled them, degroote_muscles replaces every muscle by a "
           "DeGrooteFregly2016Muscle as OpenSim Moco's ModOpReplaceMusclesWithDeGrooteFregly2016 does, and "
           "ignore_passive_fiber_forces (with it) leaves their passive force out. A bad file, or flat outputs the file gives that violate "
           "Assumption 1, raise ValueError; when none the library chooses serves the joint ranges (OpenSim's often), "
           "each plan or run chooses them over the region its task visits.")
      .def_static("from_json", &from_json, py::arg("text"), py::arg("source") = "model",
                  "The model of a model file's JSON text (what to_json gives; `source` names it in messages).")
      .def("to_json", [](const Model& self) { return plugin::model_json_text(self.model->description()); },
           "The model as a model file's JSON text (from_json and Model(path) read it back to the same model).")
      .def_property_readonly(
          "name", [](const Model& self) { return self.model->description().name; })
      .def_property_readonly(
          "warnings", [](const Model& self) { return self.model->warnings(); },
          "implausible values of the model (unit mix-ups), each naming its field; also issued as UserWarning on loading")
      .def_property_readonly(
          "joints",
          [](const Model& self) {
            std::vector<std::string> names;
            for (const auto& j : self.model->description().joints) names.push_back(j.name);
            return names;
          },
          "joint names, in model order")
      .def_property_readonly(
          "joint_types",
          [](const Model& self) {
            std::vector<std::string> types;
            for (const auto& j : self.model->description().joints) types.push_back(plugin::joint_type_name(j.type));
            return types;
          },
          "each joint's type, \"pin\" (coordinate in rad) or \"slider\" (coordinate in m), in model order")
      .def_property_readonly(
          "muscles",
          [](const Model& self) {
            std::vector<std::string> names;
            for (const auto& mu : self.model->description().muscles) names.push_back(mu.parameters.name);
            return names;
          },
          "muscle names, in model order")
      .def_property_readonly(
          "flat_outputs",
          [](const Model& self) -> py::object {
            if (!self.flat) return py::none();
            return py::cast(Table(self.flat->E()));
          },
          "the flat-output matrix E (flat outputs x muscles: Y = E F): the model file's, or the library's choice over "
          "the joint ranges; None when none holds over the ranges (each plan or run then chooses E over its task)")
      .def_property_readonly(
          "max_isometric_forces",
          [](const Model& self) {
            Eigen::VectorXd f(self.model->numMuscles());
            for (int j = 0; j < self.model->numMuscles(); ++j) f[j] = self.model->muscle(j).getParameters().max_isometric_force_N;
            return f;
          },
          "each muscle's maximum isometric force, N (model order)")
      .def_property_readonly(
          "coordinates",
          [](const Model& self) {
            std::vector<std::string> names;
            for (const auto& j : self.model->description().joints) names.push_back(j.coordinateName());
            return names;
          },
          "each joint's coordinate name, in model order (OpenSim's, for imported models)")
      .def_property_readonly(
          "held_coordinates",
          [](const Model& self) {
            std::map<std::string, double> held;
            for (const auto& mu : self.model->description().muscles)
              if (mu.polynomial_path) held.insert(mu.polynomial_path->held_coordinates_rad.begin(), mu.polynomial_path->held_coordinates_rad.end());
            return held;
          },
          "coordinates of the original model held fixed in this one (rad, by name; imported models)")
      .def("body_frames", &body_frames, py::arg("q"),
           "Each joint's child body in the ground frame at posture q (rad; a slider's m): (origins, joints x 3, m; "
           "rotations, joints x 3 x 3, body to ground).")
      .def(
          "moment_arms",
          [](const Model& self, const py::object& q) {
            const Eigen::VectorXd q_rad = vector_argument(q, self.model->numJoints(), "q");
            if (!q_rad.allFinite()) throw py::value_error("q: coordinates must be finite");
            return Table(self.model->momentArmMatrix(q_rad).transpose());
          },
          py::arg("q"),
          "The moment arms at posture q (rad; a slider's m): muscles x joints, m, r = -dL/dq (positive: the "
          "muscle shortens as the coordinate grows).")
      .def("with_strength", &with_strength, py::arg("factors"),
           "A copy with each muscle's maximum isometric force multiplied by its factor (one number for all, or one "
           "per muscle; positive), with the same flat outputs. Bad factors raise ValueError.")
      .def("__repr__", [](const Model& self) {
        return "<flatsos.Model '" + self.model->description().name + "': " + std::to_string(self.model->numJoints()) +
               " joints, " + std::to_string(self.model->numMuscles()) + " muscles>";
      });
}

}  // namespace flatsos::python
