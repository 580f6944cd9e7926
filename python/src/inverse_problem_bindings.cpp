// flatsos.solve_inverse: the inverse problem along a measured motion (what OpenSim's MocoInverse
// solves).
#include "bindings.hpp"

#include <string>

#include "flatsos/planner/inverse_problem.hpp"
#include "flatsos/planner/joint_reference.hpp"
#include "flatsos/planner/static_optimization.hpp"
#include "flatsos/planner/tracking.hpp"

namespace py = pybind11;

namespace flatsos::python {

namespace {

py::dict solve_inverse(const Model& m, const std::string& motion_file, const py::object& effort, const py::object& weights,
                       const py::object& reserves, double cutoff_hz) {
  const plugin::MusculoskeletalModel& model = *m.model;
  const std::shared_ptr<const planner::Effort> chosen = effort_argument(effort, weights, model.numMuscles());
  planner::InverseProblemOptions o;
  o.reserves_N = vector_argument(reserves, model.numMuscles(), "reserves", true);
  planner::InverseProblemResult r;
  {
    py::gil_scoped_release release;
    const plugin::ProcessedCoordinates motion = planner::read_motion_for(model, motion_file, cutoff_hz);
    const planner::JointReference reference = planner::JointReference::fromMotion(model, motion);
    auto flat = flat_for_task(m, planner::reference_postures(reference, motion.report_times_s));
    o.effort = chosen ? chosen : flat->effort();  // None and "paper": the model's linear effort
    r = planner::solve_inverse_problem(*flat, motion, o);
  }
  py::dict out;
  out["time"] = Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(r.time_s.data(), static_cast<Eigen::Index>(r.time_s.size())));
  out["activation"] = Table(r.activation);
  out["excitation"] = Table(r.excitation);
  out["tendon_force"] = Table(r.tendon_force_N);
  out["effort"] = r.effort_name;
  out["effort_value"] = r.effort_value;
  out["effort_unit"] = r.effort_unit;
  out["success"] = r.status == planner::SolveStatus::Solved;
  out["status"] = planner::to_string(r.status);
  out["message"] = r.message;
  out["wall_seconds"] = r.wall_seconds;
  return out;
}

}  // namespace

void register_inverse_problem(py::module_& m) {
  m.def("solve_inverse", &solve_inverse, py::arg("model"), py::arg("motion_file"), py::kw_only(),
        py::arg("effort") = "excitation_squared", py::arg("weights") = py::none(), py::arg("reserves") = 1.0,
        py::arg("cutoff_hz") = 6.0,
        "The inverse problem along a measured motion, as OpenSim's MocoInverse solves it: the least effort that "
        "moves the model's muscles, with their dynamics, along the motion (an OpenSim coordinates table, .mot or "
        ".sto, filtered at `cutoff_hz` and splined as OpenSim's tools do), for the whole motion at once, every "
        "excitation in [0, 1] and activation in [floor, 1], every tendon force at least `reserves` (N, one or one "
        "per muscle). effort: 'excitation_squared' (MocoInverse's), another name of the efforts or None / "
        "'paper' (the model's linear effort), weighted per muscle by `weights`. Smooth muscle laws converge best "
        "(Model(..., degroote_muscles=True), as MocoInverse's examples do). Returns a dict: 'time' (s, the "
        "motion's frames), 'activation', 'excitation' and 'tendon_force' (N; one row per frame, one column per "
        "muscle), 'effort', 'effort_value', 'effort_unit', 'success', 'status', 'message', 'wall_seconds'. "
        "Releases the GIL.");
}

}  // namespace flatsos::python
