// flatsos.simulate_plan: Simbody runs a plan's excitations open loop from the plan's own start;
// flatsos.simulate: Simbody runs given excitations (a controls file or arrays) from a given state.
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "flatsos/planner/planned_excitation.hpp"
#include "flatsos/plugin/force/excitation_signal.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"
#include "flatsos/plugin/integration/stepper.hpp"
#include "flatsos/plugin/io/excitation_file.hpp"
#include "flatsos/plugin/io/state_table.hpp"
#include "flatsos/plugin/model/static_equilibrium.hpp"

namespace py = pybind11;

namespace flatsos::python {

namespace {

// The integrator settings both entry points take; ValueError naming the argument.
plugin::SimulationOptions simulation_options(double duration_s, double accuracy,
                                             const std::string& integrator, int reports,
                                             long max_steps) {
  if (!(duration_s > 0.0) || !std::isfinite(duration_s))
    throw py::value_error("duration: must be a positive number of seconds");
  if (!(accuracy > 0.0 && accuracy <= 1e-3))
    throw py::value_error("accuracy: must lie in (0, 1e-3]");
  if (reports < 1) throw py::value_error("reports: must be at least 1");
  if (max_steps < 0) throw py::value_error("max_steps: must be >= 0 (0: no limit)");
  plugin::SimulationOptions so;
  so.integrator = plugin::integrator_from_name(
      integrator);  // std::invalid_argument (ValueError) naming the choices
  so.duration_s = duration_s;
  so.accuracy = accuracy;
  so.report_interval_s = duration_s / reports;
  so.max_steps = max_steps;
  return so;
}

// A run's tables as numpy: the states, the tendon forces and the excitations applied, one row per
// report.
py::dict simulation_result(const plugin::MusculoskeletalModel& model,
                           const plugin::SimulationResult& sim) {
  py::dict out;
  out["time"] = column_vector(sim.states, "time");
  out["q"] = columns_table(sim.states, joint_value_columns(model));
  out["activation"] = columns_table(sim.states, muscle_columns(model, "/activation"));
  out["tendon_force"] = columns_table(sim.states, muscle_columns(model, "/tendon_force"));
  out["excitation"] = columns_table(sim.controls, muscle_columns(model, ""));
  out["finite"] = sim.finite;
  out["completed"] = sim.completed();
  out["step_limit_reached"] = sim.step_limit_reached;
  out["message"] = sim.message;
  out["integrator_steps"] = sim.integrator_steps;
  out["integrator"] = plugin::integrator_name(sim.integrator);
  return out;
}

using Signals = std::vector<std::shared_ptr<const plugin::ExcitationSignal>>;

// Each muscle's excitation: from a controls .sto or CSV file, or from a (time, rows x muscles)
// pair of arrays; linear between rows and held after the last, as the files are.
Signals excitation_signals(const plugin::MusculoskeletalModel& model,
                           const py::object& excitation) {
  std::vector<std::string> names;
  for (const auto& md : model.description().muscles) names.push_back(md.parameters.name);
  if (py::isinstance<py::str>(excitation) || py::hasattr(excitation, "__fspath__"))
    return plugin::read_excitation_file(py::str(excitation).cast<std::string>(), names);
  if (!py::isinstance<py::tuple>(excitation) || py::len(excitation) != 2)
    throw py::value_error("excitation: a controls file, or a pair (time, excitation) of arrays");
  const py::tuple pair = excitation.cast<py::tuple>();
  const Eigen::VectorXd time = pair[0].cast<Eigen::VectorXd>();
  const Eigen::MatrixXd values = pair[1].cast<Eigen::MatrixXd>();
  if (values.rows() != time.size() || values.cols() != model.numMuscles())
    throw py::value_error("excitation: expected " + std::to_string(time.size()) + " rows of " +
                          std::to_string(model.numMuscles()) +
                          " excitations (a column per muscle), got " +
                          std::to_string(values.rows()) + " x " + std::to_string(values.cols()));
  if (!values.allFinite() || values.minCoeff() < 0.0 || values.maxCoeff() > 1.0)
    throw py::value_error("excitation: values must lie in [0, 1]");
  const std::vector<double> times(time.data(), time.data() + time.size());
  Signals signals;
  for (Eigen::Index j = 0; j < values.cols(); ++j) {
    const Eigen::VectorXd column =
        values.col(j);  // PiecewiseLinearSignal: ValueError for bad times
    signals.push_back(std::make_shared<const plugin::PiecewiseLinearSignal>(
        times, std::vector<double>(column.data(), column.data() + column.size())));
  }
  return signals;
}

py::dict simulate(const Model& m, const py::object& q0, const py::object& qd0, const py::object& a0,
                  const py::object& excitation, double duration, double accuracy,
                  const std::string& integrator, int reports, long max_steps) {
  const plugin::MusculoskeletalModel& model = *m.model;
  const Eigen::VectorXd q = vector_argument(q0, model.numJoints(), "q0");
  const Eigen::VectorXd qd = vector_argument(qd0, model.numJoints(), "qd0");
  const Eigen::VectorXd a = vector_argument(a0, model.numMuscles(), "a0", true);
  if (!((a.array() > 0.0).all() && (a.array() <= 1.0).all()))
    throw py::value_error("a0: activations must lie in (0, 1]");
  const plugin::SimulationOptions so =
      simulation_options(duration, accuracy, integrator, reports, max_steps);
  const Signals signals = excitation_signals(model, excitation);
  plugin::SimulationResult sim;
  {
    py::gil_scoped_release release;
    SimTK::State s = model.defaultState();
    model.setJointAngles(s, q);
    model.setJointSpeeds(s, qd);
    plugin::equilibrate_tendons(model, s, a);
    for (int j = 0; j < model.numMuscles(); ++j) model.muscle(j).setExcitationSignal(s, signals[j]);
    sim = plugin::simulate(model, s, so);
  }
  return simulation_result(model, sim);
}

py::dict simulate_plan(const Plan& p, double accuracy, const std::string& integrator, int reports,
                       long max_steps) {
  if (p.plan.status != planner::SolveStatus::Solved || !p.plan.Y)
    throw py::value_error(std::string("the plan is ") + planner::to_string(p.plan.status) +
                          ", nothing to simulate: " + p.plan.message);
  const plugin::SimulationOptions so =
      simulation_options(p.plan.path.duration_s, accuracy, integrator, reports, max_steps);
  const plugin::MusculoskeletalModel& model = *p.model;
  plugin::SimulationResult sim;
  {
    py::gil_scoped_release release;
    SimTK::State s = p.initial;
    const auto excitation = planner::PlannedExcitation::create(*p.flat, p.plan.path, *p.plan.Y);
    for (int j = 0; j < model.numMuscles(); ++j)
      model.muscle(j).setExcitationSignal(s, excitation->signal(j));
    sim = plugin::simulate(model, s, so);
  }
  return simulation_result(model, sim);
}

constexpr const char* kResultDoc =
    "Returns a dict: 'time' (s), 'q' (rad, one row per report), 'activation', 'tendon_force' (N) "
    "and "
    "'excitation' (one column per muscle), 'finite' (False: a state became NaN and the run "
    "stopped, 'message' "
    "says where), 'step_limit_reached' (True: it stopped after `max_steps` integrator steps; 0: no "
    "limit), "
    "'completed' (the whole duration), 'integrator_steps', 'integrator' (the one used). integrator: "
    "'rkm', 'bdf', 'rosenbrock' or 'auto' (rkm, bdf where the muscles are stiff at the start); `reports` "
    "rows after the first. Releases the GIL while it integrates.";

}  // namespace

void register_simulation(py::module_& m) {
  // Docstrings that outlive the module's definition (pybind11 keeps the pointer).
  static const std::string simulate_plan_doc =
      std::string(
          "Simulates a solved plan open loop in Simbody from the state it was planned from: the "
          "muscles "
          "driven by the planned excitations. ") +
      kResultDoc;
  static const std::string simulate_doc =
      std::string(
          "Simulates the model in Simbody under given excitations (what `flatsos simulate` does): "
          "from "
          "joint angles q0 (rad) and speeds qd0 with activations a0, each tendon in static "
          "equilibrium, "
          "for `duration` s. excitation: a controls .sto (OpenSim Moco's) or CSV file, or a pair "
          "(time, excitation: rows x muscles) of arrays; linear between rows, held after the "
          "last. ") +
      kResultDoc;
  m.def("simulate_plan", &simulate_plan, py::arg("plan"), py::kw_only(),
        py::arg("accuracy") = 1e-10, py::arg("integrator") = "auto", py::arg("reports") = 300,
        py::arg("max_steps") = 1000000, simulate_plan_doc.c_str());
  m.def("simulate", &simulate, py::arg("model"), py::arg("q0"), py::arg("qd0"), py::arg("a0"),
        py::arg("excitation"), py::arg("duration"), py::kw_only(), py::arg("accuracy") = 1e-8,
        py::arg("integrator") = "rosenbrock", py::arg("reports") = 300,
        py::arg("max_steps") = 1000000, simulate_doc.c_str());
}

}  // namespace flatsos::python
