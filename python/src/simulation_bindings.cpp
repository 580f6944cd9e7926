// flatsos.simulate_plan: Simbody runs a plan's excitations open loop from the plan's own start.
#include "bindings.hpp"

#include <string>

#include "flatsos/planner/planned_excitation.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"
#include "flatsos/plugin/integration/stepper.hpp"
#include "flatsos/plugin/io/state_table.hpp"

namespace py = pybind11;

namespace flatsos::python {

namespace {

py::dict simulate_plan(const Plan& p, double accuracy, const std::string& integrator, int reports, long max_steps) {
  if (p.plan.status != planner::SolveStatus::Solved || !p.plan.Y)
    throw py::value_error(std::string("the plan is ") + planner::to_string(p.plan.status) + ", nothing to simulate: " +
                          p.plan.message);
  if (!(accuracy > 0.0 && accuracy <= 1e-3)) throw py::value_error("accuracy: must lie in (0, 1e-3]");
  if (reports < 1) throw py::value_error("reports: must be at least 1");
  if (max_steps < 0) throw py::value_error("max_steps: must be >= 0 (0: no limit)");
  plugin::SimulationOptions so;
  so.integrator = plugin::integrator_from_name(integrator);  // std::invalid_argument (ValueError) naming the choices
  so.duration_s = p.plan.path.duration_s;
  so.accuracy = accuracy;
  so.report_interval_s = so.duration_s / reports;
  so.max_steps = max_steps;
  const plugin::MusculoskeletalModel& model = *p.model;
  plugin::SimulationResult sim;
  {
    py::gil_scoped_release release;
    SimTK::State s = p.initial;
    const auto excitation = planner::PlannedExcitation::create(*p.flat, p.plan.path, *p.plan.Y);
    for (int j = 0; j < model.numMuscles(); ++j) model.muscle(j).setExcitationSignal(s, excitation->signal(j));
    sim = plugin::simulate(model, s, so);
  }
  py::dict out;
  out["time"] = column_vector(sim.states, "time");
  out["q"] = columns_table(sim.states, joint_value_columns(model));
  out["activation"] = columns_table(sim.states, muscle_columns(model, "/activation"));
  out["finite"] = sim.finite;
  out["completed"] = sim.completed();
  out["step_limit_reached"] = sim.step_limit_reached;
  out["message"] = sim.message;
  out["integrator_steps"] = sim.integrator_steps;
  return out;
}

}  // namespace

void register_simulation(py::module_& m) {
  m.def("simulate_plan", &simulate_plan, py::arg("plan"), py::kw_only(), py::arg("accuracy") = 1e-10,
        py::arg("integrator") = "rkm", py::arg("reports") = 300, py::arg("max_steps") = 1000000,
        "Simulates a solved plan open loop in Simbody from the state it was planned from: the muscles driven by the "
        "planned excitations. Returns a dict: 'time' (s), 'q' (rad, one row per report), 'activation' (one column "
        "per muscle), 'finite' (False: a state became NaN and the run stopped, 'message' says where), "
        "'step_limit_reached' (True: it stopped after `max_steps` integrator steps; 0: no limit), 'completed' "
        "(the whole duration), 'integrator_steps'. integrator: 'rkm', 'bdf' or 'rosenbrock'; `reports` rows after the first. Releases "
        "the GIL while it integrates.");
}

}  // namespace flatsos::python
