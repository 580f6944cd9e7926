// flatsos.plan_open_loop and the plan it returns.
#include "bindings.hpp"

#include <cmath>
#include <optional>
#include <string>

#include "flatsos/planner/open_loop_study.hpp"
#include "flatsos/planner/rest_state.hpp"
#include "flatsos/planner/shortest_transfer.hpp"


namespace py = pybind11;

namespace flatsos::python {

namespace {

// The options and start state both entry points share; bad input raises ValueError.
struct OpenLoopInputs {
  planner::OpenLoopOptions options;
  planner::OpenLoopStudyOptions study;  // torque_degree and method
  Eigen::VectorXd q0_rad, qd0_rad_per_s;
  std::optional<Eigen::VectorXd> activations;
};

// The basis keywords: a preset, and each of its values unless given (None).
struct BasisArguments {
  std::string preset;
  std::optional<int> flat_output_degree, flat_output_spans;
  std::optional<double> flat_output_span_growth;
  std::optional<int> torque_pieces;
  std::optional<double> torque_piece_growth;
  std::optional<int> torque_degree;
  bool bounds = true;
};

planner::OpenLoopOptions preset_options(const BasisArguments& b) {
  planner::OpenLoopOptions o;
  try {
    o = planner::open_loop_options(planner::preset_named(b.preset));
  } catch (const std::invalid_argument& e) {
    throw py::value_error(std::string("preset: ") + e.what());
  }
  o.sos.flat_output_degree = b.flat_output_degree.value_or(o.sos.flat_output_degree);
  o.sos.flat_output_spans = b.flat_output_spans.value_or(o.sos.flat_output_spans);
  o.sos.flat_output_span_growth = b.flat_output_span_growth.value_or(o.sos.flat_output_span_growth);
  o.torque.pieces = b.torque_pieces.value_or(o.torque.pieces);
  o.torque.piece_growth = b.torque_piece_growth.value_or(o.torque.piece_growth);
  o.sos.bounds.enforce = b.bounds;
  return o;
}

OpenLoopInputs open_loop_inputs(const Model& m, const py::object& q0, const py::object& qd0, const py::object& a0,
                                const py::object& target, double duration, const py::object& reserves,
                                const BasisArguments& basis) {
  const plugin::MusculoskeletalModel& model = *m.model;
  const Eigen::Index joints = model.numJoints(), muscles = model.numMuscles();
  OpenLoopInputs in;
  in.q0_rad = vector_argument(q0, joints, "q0");
  in.qd0_rad_per_s = vector_argument(qd0, joints, "qd0");
  in.activations = activations_argument(a0, muscles);
  if (!(duration > 0.0) || !std::isfinite(duration)) throw py::value_error("duration: must be a positive number of seconds");
  in.options = preset_options(basis);
  in.study.torque.degree = basis.torque_degree.value_or(in.study.torque.degree);
  planner::OpenLoopOptions& o = in.options;
  o.duration_s = duration;
  o.target_q_rad = vector_argument(target, joints, "target");
  o.reserves_N = vector_argument(reserves, muscles, "reserves", true);
  return in;
}

Plan plan_open_loop(const Model& m, const py::object& q0, const py::object& qd0, const py::object& a0,
                    const py::object& target, double duration, const py::object& reserves, const std::string& preset,
                    std::optional<int> flat_output_degree, std::optional<int> flat_output_spans,
                    std::optional<double> flat_output_span_growth, std::optional<int> torque_pieces,
                    std::optional<double> torque_piece_growth, std::optional<int> torque_degree, bool bounds,
                    const std::string& method, const py::object& effort, const py::object& weights,
                    int free_path_spans, double free_path_span_growth) {
  OpenLoopInputs in = open_loop_inputs(m, q0, qd0, a0, target, duration, reserves,
                                       {preset, flat_output_degree, flat_output_spans, flat_output_span_growth,
                                        torque_pieces, torque_piece_growth, torque_degree, bounds});
  in.options.effort = effort_argument(effort, weights, m.model->numMuscles());
  if (free_path_spans < 0) throw py::value_error("free_path_spans: must be >= 0 (0: the prescribed path)");
  if (!(free_path_span_growth > 0.0)) throw py::value_error("free_path_span_growth: must be > 0");
  in.options.free_path.enabled = free_path_spans > 0;
  if (free_path_spans > 0) in.options.free_path.spans = free_path_spans;
  in.options.free_path.span_growth = free_path_span_growth;
  try {
    in.study.sos.method = planner::sos_program_method(method);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(std::string("method: ") + e.what());
  }
  Plan out{m.model, nullptr, {}, {}};
  py::gil_scoped_release release;
  out.flat = flat_for_task(m, {in.q0_rad, in.options.target_q_rad});
  const SimTK::State s = planner::start_state(*out.flat, in.q0_rad, in.qd0_rad_per_s, in.activations, in.options.reserves_N);
  out.plan = planner::plan_open_loop(*out.flat, planner::muscle_state_of(*m.model, s), in.options, in.study);
  out.initial = s;
  return out;
}

py::dict shortest_transfer(const Model& m, const py::object& q0, const py::object& qd0, const py::object& a0,
                           const py::object& target, const py::object& reserves, double longest, double shortest,
                           double ratio, double tolerance, const std::string& preset,
                           std::optional<int> flat_output_degree, std::optional<int> flat_output_spans,
                           std::optional<double> flat_output_span_growth, std::optional<int> torque_pieces,
                           std::optional<double> torque_piece_growth, std::optional<int> torque_degree, bool bounds) {
  const OpenLoopInputs in =
      open_loop_inputs(m, q0, qd0, a0, target, longest, reserves,
                       {preset, flat_output_degree, flat_output_spans, flat_output_span_growth, torque_pieces,
                        torque_piece_growth, torque_degree, bounds});
  planner::ShortestTransferOptions so;
  so.lower_s = shortest;
  so.upper_s = longest;
  so.scan_ratio = ratio;
  so.tolerance_s = tolerance;
  Plan plan{m.model, nullptr, {}, {}};
  planner::ShortestTransfer r;
  {
    py::gil_scoped_release release;  // pybind11 raises std::invalid_argument as ValueError
    plan.flat = flat_for_task(m, {in.q0_rad, in.options.target_q_rad});
    const SimTK::State s = planner::start_state(*plan.flat, in.q0_rad, in.qd0_rad_per_s, in.activations, in.options.reserves_N);
    plugin::ModelWorkspace workspace = plan.flat->makeWorkspace();
    r = planner::shortest_transfer(*plan.flat, workspace, planner::muscle_state_of(*m.model, s), in.options, so, in.study);
    plan.initial = s;
  }
  py::list tried;
  for (const auto& t : r.tried) {
    py::dict d;
    d["duration"] = t.duration_s;
    d["status"] = planner::to_string(t.status);
    d["cost"] = t.status == planner::SolveStatus::Solved ? py::cast(t.cost_N_s) : py::none();
    d["message"] = t.message;
    d["seconds"] = t.seconds;
    tried.append(d);
  }
  py::dict out;
  out["status"] = planner::to_string(r.status);
  out["message"] = r.message;
  out["shortest"] = r.status == planner::SolveStatus::Solved ? py::cast(r.shortest_s) : py::none();
  out["no_plan_below"] = r.no_plan_below_s > 0.0 ? py::cast(r.no_plan_below_s) : py::none();
  out["below_status"] = planner::to_string(r.below_status);
  out["at_lower_end"] = r.at_lower_end;
  out["tried"] = tried;
  out["seconds"] = r.seconds;
  plan.plan = std::move(r.plan);
  out["plan"] = py::cast(std::move(plan));
  return out;
}

py::dict sample(const Plan& self, const Eigen::VectorXd& times) {
  if (self.plan.status != planner::SolveStatus::Solved || !self.plan.Y)
    throw py::value_error(std::string("the plan is ") + planner::to_string(self.plan.status) + ", nothing to sample: " +
                          self.plan.message);
  const double T = self.plan.path.duration_s;
  for (Eigen::Index i = 0; i < times.size(); ++i)
    if (!(times[i] >= 0.0 && times[i] <= T))
      throw py::value_error("times: " + std::to_string(times[i]) + " s is outside the plan's [0, " + std::to_string(T) + "] s");
  const Eigen::Index n = times.size(), joints = self.model->numJoints(), muscles = self.model->numMuscles();
  Table q(n, joints), activation(n, muscles), excitation(n, muscles), force(n, muscles);
  {
    py::gil_scoped_release release;
    plugin::ModelWorkspace workspace = self.flat->makeWorkspace();
    for (Eigen::Index i = 0; i < n; ++i) {
      const planner::Jet qj = self.plan.jointJet(times[i]);
      const planner::MusclePoint p = self.flat->inverse(workspace, qj, self.plan.flatOutputJet(times[i]));
      q.row(i) = qj.col(0).transpose();
      activation.row(i) = p.activation.transpose();
      excitation.row(i) = p.excitation.transpose();
      force.row(i) = p.tendon_force_N.transpose();
    }
  }
  py::dict out;
  out["time"] = times;
  out["q"] = q;
  out["activation"] = activation;
  out["excitation"] = excitation;
  out["tendon_force"] = force;
  return out;
}

std::string cost_unit(const Plan& p) {
  return p.plan.sos.effort_unit.empty() ? p.flat->effortUnit() : p.plan.sos.effort_unit;
}

}  // namespace

void register_open_loop(py::module_& m) {
  py::class_<Plan>(m, "OpenLoopPlan", "An open-loop plan: its status, cost and samples.")
      .def_property_readonly("status", [](const Plan& p) { return std::string(planner::to_string(p.plan.status)); },
                             "'solved', 'infeasible' or 'failed'")
      .def_property_readonly("message", [](const Plan& p) { return p.plan.message; }, "why, when not solved")
      .def_property_readonly(
          "cost",
          [](const Plan& p) -> std::optional<double> {
            if (p.plan.status != planner::SolveStatus::Solved) return std::nullopt;
            return p.plan.sos.effort_value;
          },
          "the effort's value, in cost_unit (None when not solved)")
      .def_property_readonly("cost_unit", [](const Plan& p) { return cost_unit(p); },
                             "'N s' (tendon forces), or 's' (normalized tendon forces, the library's choice of flat "
                             "outputs, and the efforts of excitations, activations and stresses)")
      .def_property_readonly(
          "effort", [](const Plan& p) { return p.plan.sos.effort_name.empty() ? "tendon_force" : p.plan.sos.effort_name; },
          "what the plan minimized: 'tendon_force' (the model's linear effort, the paper's) or the effort's name")
      .def_property_readonly("duration", [](const Plan& p) { return p.plan.path.duration_s; }, "s")
      .def_property_readonly("warnings", [](const Plan& p) { return p.plan.warnings; })
      .def_property_readonly(
          "seconds",
          [](const Plan& p) {
            py::dict d;
            d["setup"] = p.plan.setup_seconds;
            d["solve"] = p.plan.solve_seconds;
            d["certify"] = p.plan.certify_seconds;
            d["check"] = p.plan.check_seconds;
            return d;
          },
          "where the planning time went, s")
      .def_property_readonly(
          "sos",
          [](const Plan& p) {
            const planner::SosProgramResult& r = p.plan.sos;
            py::dict d;
            d["method"] = r.method;
            d["ipopt_iterations"] = r.ipopt_iterations;
            d["ipopt_calls"] = r.ipopt_calls;
            d["ipopt_linear_solver"] = r.ipopt_linear_solver;
            d["exchange_rounds"] = r.exchange_rounds;
            d["certified"] = r.certified;
            d["certified_pieces"] = r.certified_pieces;
            d["near_active_pieces"] = r.near_active_pieces;
            if (p.plan.Y) d["flat_output_breakpoints"] = p.plan.Y->basis().breakpoints();
            std::vector<double> piece_starts;
            for (const auto& piece : p.plan.torque.pieces) piece_starts.push_back(piece.t0_s);
            d["torque_piece_starts"] = piece_starts;
            if (r.method == "whole_program_nlp") {
              d["nlp_variables"] = r.nlp_variables;
              d["nlp_equalities"] = r.nlp_equalities;
              d["max_certificate_residual"] = r.max_certificate_residual_N;
            }
            return d;
          },
          "how the reserves' program was solved: 'method', Ipopt's iterations, calls and linear solver, "
          "'exchange_rounds', the certificates ('certified', 'certified_pieces' of 'near_active_pieces'), the flat "
          "outputs' 'flat_output_breakpoints' and the 'torque_piece_starts' (s) and, for 'whole_program_nlp', its 'nlp_variables', 'nlp_equalities' and 'max_certificate_residual' (N)")
      .def_property_readonly(
          "free_path",
          [](const Plan& p) -> py::object {
            const planner::FreePathReport& r = p.plan.free_path;
            if (!r.optimized && r.prescribed_status.empty()) return py::none();
            py::dict d;
            d["optimized"] = r.optimized;
            d["prescribed_cost"] = r.prescribed_cost_N_s;
            d["prescribed_status"] = r.prescribed_status;
            d["cost_at_points"] = r.cost_at_points_N_s;
            d["method"] = std::string(planner::to_string(r.method));
            d["rounds"] = r.rounds;
            d["points"] = r.points;
            d["path_iterations"] = r.path_iterations;
            return std::move(d);
          },
          "with free_path_spans: what optimizing the joint path did ('optimized', the plan along the prescribed "
          "path's 'prescribed_cost' and 'prescribed_status', 'cost_at_points', 'method', 'rounds', 'points', "
          "'path_iterations'; costs in cost_unit); None along the prescribed path")
      .def("sample", &sample, py::arg("times"),
           "The plan at `times` (s, within [0, duration]): a dict of numpy arrays 'time', 'q' (rad, one row per "
           "time, one column per joint), 'activation', 'excitation' and 'tendon_force' (N; one column per muscle).")
      .def("__repr__", [](const Plan& p) {
        return std::string("<flatsos.OpenLoopPlan ") + planner::to_string(p.plan.status) +
               (p.plan.status == planner::SolveStatus::Solved
                    ? ", " + p.plan.sos.effort_name + " " + std::to_string(p.plan.sos.effort_value) + " " + cost_unit(p)
                    : "") +
               ">";
      });

  m.def("plan_open_loop", &plan_open_loop, py::arg("model"), py::arg("q0"), py::arg("qd0"), py::arg("a0"),
        py::arg("target"), py::arg("duration"), py::arg("reserves"), py::kw_only(), py::arg("preset") = "best",
        py::arg("flat_output_degree") = py::none(), py::arg("flat_output_spans") = py::none(),
        py::arg("flat_output_span_growth") = py::none(), py::arg("torque_pieces") = py::none(),
        py::arg("torque_piece_growth") = py::none(), py::arg("torque_degree") = py::none(), py::arg("bounds") = true,
        py::arg("method") = "exchange", py::arg("effort") = py::none(), py::arg("weights") = py::none(),
        py::arg("free_path_spans") = 0, py::arg("free_path_span_growth") = 1.0,
        "Minimum-effort open-loop plan from the initial state to rest at `target` in `duration` s.\n"
        "q0, qd0, target: rad and rad/s, one per joint; a0: initial activations in (0, 1], one per muscle, with "
        "tendons in static equilibrium (None: the minimum-effort rest state at q0); reserves: minimum tendon "
        "force, N, one number or one per muscle. Keywords: `preset`, 'best' (quintic B-splines on 48 spans, 48 "
        "cubic torque pieces: the default) or 'paper' (Richter & Warner's single quartic, 12 pieces); then, each "
        "overriding the preset's value where given, the flat outputs' B-spline degree and spans and how much longer each span is than the one before (1: uniform; above 1: short "
        "spans where a fast transfer starts; by default 1 for the linear effort, 1.06 for the others), the torque model's pieces, their growth likewise, and degree, and whether excitations and activations are "
        "kept within their bounds; `method`: 'exchange' (the default) or 'whole_program_nlp' (the whole program as one "
        "Ipopt problem, the reference formulation, which checks the bounds instead of imposing them); `effort`: "
        "None or 'paper' (the model's linear effort in the tendon forces, its effort_weights), or "
        "'excitation_squared', 'excitation_cubed', 'activation_squared', 'activation_cubed', 'stress_squared', "
        "'stress_cubed' (the integral of sum w_j x_j^p, minimized along the prescribed path from the linear "
        "optimum), with `weights` w_j (None: 1 each); `free_path_spans` > 0 optimizes the joint path too, a B-spline on that "
        "many spans through the same boundary conditions, each `free_path_span_growth` times the one before (0: the "
        "prescribed degree-8 path). Bad input raises ValueError; the GIL is released while planning.");

  m.def("shortest_transfer", &shortest_transfer, py::arg("model"), py::arg("q0"), py::arg("qd0"), py::arg("a0"),
        py::arg("target"), py::arg("reserves"), py::kw_only(), py::arg("longest"), py::arg("shortest") = 0.1,
        py::arg("ratio") = 0.8, py::arg("tolerance") = 1e-3, py::arg("preset") = "best",
        py::arg("flat_output_degree") = py::none(), py::arg("flat_output_spans") = py::none(),
        py::arg("flat_output_span_growth") = py::none(), py::arg("torque_pieces") = py::none(),
        py::arg("torque_piece_growth") = py::none(), py::arg("torque_degree") = py::none(), py::arg("bounds") = true,
        "The shortest duration (s) with a plan for this transfer: searched down from `longest` (which must have "
        "one) in steps of `ratio`, no further than `shortest`, then bisected to `tolerance`. Returns a dict: "
        "'status' ('solved', 'infeasible': no plan at `longest`, 'failed'), 'message', 'shortest' (None unless "
        "solved), 'no_plan_below' (the longest duration found without a plan, None if none), 'below_status' "
        "('infeasible': proven there; 'failed': undecided, so 'shortest' is an upper bound), 'at_lower_end', "
        "'tried' (every planned duration: 'duration', 'status', 'cost', 'message', 'seconds'), 'seconds' and "
        "'plan' (the OpenLoopPlan at 'shortest', else at `longest`). Other arguments as plan_open_loop's.");
}

}  // namespace flatsos::python
