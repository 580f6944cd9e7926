// flatsos.static_optimization: OpenSim's static optimization along a measured motion.
#include "bindings.hpp"

#include <string>

#include "flatsos/planner/static_optimization.hpp"

namespace py = pybind11;

namespace flatsos::python {

namespace {

py::dict static_optimization(const Model& m, const std::string& motion_file, const std::string& effort,
                             const py::object& weights, double reserve_optimal_torque, double cutoff_hz,
                             const py::object& strength_rule) {
  const plugin::MusculoskeletalModel& model = *m.model;
  planner::StaticOptimizationOptions o;
  const Eigen::VectorXd w = weights.is_none() ? Eigen::VectorXd()
                                              : vector_argument(weights, model.numMuscles(), "weights", true);
  o.effort = planner::effort_named(effort, w);  // ValueError naming the known efforts
  o.reserve_optimal_torque_N_m = reserve_optimal_torque;
  if (!strength_rule.is_none()) {
    const std::string rule = py::cast<std::string>(strength_rule);
    if (rule != "opensim2" && rule != "rigid_tendon")
      throw py::value_error("strength_rule: 'opensim2', 'rigid_tendon' or None (by the muscles' model), not '" + rule + "'");
    o.strength_rule = rule == "opensim2" ? planner::MuscleStrengthRule::OpenSim2 : planner::MuscleStrengthRule::RigidTendon;
  }
  planner::StaticOptimizationResult r;
  {
    py::gil_scoped_release release;
    const plugin::ProcessedCoordinates motion = planner::read_motion_for(model, motion_file, cutoff_hz);
    r = planner::static_optimization(model, motion, o);
  }
  py::dict out;
  out["time"] = Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(r.time_s.data(), static_cast<Eigen::Index>(r.time_s.size())));
  out["activation"] = Table(r.activation);
  out["tendon_force"] = Table(r.tendon_force_N);
  out["reserve_torque"] = Table(r.reserve_torque_N_m);
  out["effort"] = r.effort;
  out["strength_rule"] = r.strength_rule == planner::MuscleStrengthRule::OpenSim2 ? "opensim2" : "rigid_tendon";
  out["success"] = r.success();
  out["message"] = r.success() ? std::string() : r.failures.front();
  out["failures"] = r.failures;
  out["wall_seconds"] = r.wall_seconds;
  return out;
}

}  // namespace

void register_static_optimization(py::module_& m) {
  m.def("static_optimization", &static_optimization, py::arg("model"), py::arg("motion_file"), py::kw_only(),
        py::arg("effort") = "activation_squared", py::arg("weights") = py::none(), py::arg("reserve_optimal_torque") = 0.0,
        py::arg("cutoff_hz") = 6.0, py::arg("strength_rule") = py::none(),
        "Static optimization along a measured motion, as OpenSim's StaticOptimization tool solves it. The motion "
        "(an OpenSim coordinates table, .mot or .sto, degrees or radians as its header says) is filtered at "
        "`cutoff_hz` and splined as OpenSim's tools do; at each frame the activations in [0, 1] of least effort make "
        "the muscles produce the inverse-dynamics torques. effort: 'activation_squared' (OpenSim's), "
        "'activation_cubed', 'stress_squared' or 'stress_cubed', weighted per muscle by `weights`. A model loaded "
        "with paths='geometry' uses its GeometryPaths. reserve_optimal_torque: one reserve actuator per joint "
        "(N m), 0: none. strength_rule: a muscle's force per activation, 'opensim2' (OpenSim 2.x's, the default "
        "for opensim_2_muscles) or 'rigid_tendon' (OpenSim 4's). Static optimization has no activation "
        "dynamics, so no excitations. Returns a dict: 'time' (s), 'activation' and 'tendon_force' (N; one row "
        "per frame, one column per muscle), 'reserve_torque' (one column per joint), 'effort' (per frame), "
        "'strength_rule', 'success', 'message' (the first frame the muscles could not balance), 'failures', "
        "'wall_seconds'. Releases the GIL.");
}

}  // namespace flatsos::python
