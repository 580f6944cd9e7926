#include "example_support.hpp"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <sstream>

#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"

namespace flatsos::examples {

Eigen::VectorXd to_vector(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

Eigen::VectorXd to_display(const plugin::ModelDescription& model, const Eigen::VectorXd& q_si) {
  Eigen::VectorXd out = q_si;
  for (Eigen::Index i = 0; i < out.size(); ++i)
    out[i] = i < model.numJoints() ? out[i] * model.joints[static_cast<std::size_t>(i)].displayPerSI() : out[i] / kRadPerDeg;
  return out;
}

Eigen::VectorXd from_display(const plugin::ModelDescription& model, const Eigen::VectorXd& q_shown) {
  Eigen::VectorXd out = q_shown;
  for (Eigen::Index i = 0; i < out.size(); ++i)
    if (i >= model.numJoints() || !model.joints[static_cast<std::size_t>(i)].isSlider()) out[i] *= kRadPerDeg;
  return out;
}

void require_count(const std::vector<double>& v, int n, const std::string& option) {
  if (static_cast<int>(v.size()) != n)
    throw CLI::ValidationError(option, "expects " + std::to_string(n) + " comma-separated values, got " + std::to_string(v.size()));
}

namespace {

CLI::Validator number_check(const char* name, const char* bound, bool (*holds)(double)) {
  return CLI::Validator(
      [bound, holds](std::string& text) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(text, value)) return "'" + text + "' is not a number";
        return holds(value) ? std::string() : std::string("must be ") + bound + " (got " + text + ")";
      },
      name);
}

}  // namespace

CLI::Validator positive_number() {
  return number_check("POSITIVE", "> 0", [](double v) { return v > 0.0; });
}

CLI::Validator nonnegative_number() {
  return number_check("NONNEGATIVE", ">= 0", [](double v) { return v >= 0.0; });
}

int parse_arguments(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return e.get_exit_code() == 0 ? rc : 2;
  }
  return -1;
}

CLI::Option* add_integrator_option(CLI::App& app, std::string& name, const std::string& help) {
  std::vector<std::string> names;
  for (auto kind : {plugin::IntegratorKind::RungeKuttaMerson, plugin::IntegratorKind::CPodesBdf,
                    plugin::IntegratorKind::MuscleRosenbrock, plugin::IntegratorKind::Automatic})
    names.emplace_back(plugin::integrator_name(kind));
  return app.add_option("--integrator", name, help)->capture_default_str()->check(CLI::IsMember(names));
}

CLI::Option* add_max_steps_option(CLI::App& app, long& max_steps) {
  return app
      .add_option("--max-integrator-steps", max_steps,
                  "stop the simulation after this many integrator steps and fail (0: no limit); an explicit "
                  "integrator can take millions of tiny steps where the muscles' states are stiff")
      ->capture_default_str()
      ->check(flatsos::examples::nonnegative_number());
}

Eigen::VectorXd per_muscle(const std::vector<double>& v, int m, const std::string& option) {
  if (v.size() == 1) return Eigen::VectorXd::Constant(m, v[0]);
  require_count(v, m, option);
  return to_vector(v);
}

std::vector<std::string> effort_option_names() {
  std::vector<std::string> names = planner::effort_names();
  names.insert(names.begin(), "paper");
  return names;
}

std::shared_ptr<const planner::Effort> effort_option(const std::string& name) {
  if (name == "paper" || name == "tendon_force") return nullptr;
  return planner::effort_named(name);
}

std::string format(double x) {
  std::ostringstream out;
  out << x;
  return out.str();
}

PlanTables plan_tables(const planner::FlatOutputMap& flat, const planner::OpenLoopPlan& plan,
                       const plugin::StoTable& times_from) {
  const auto& model = flat.model();
  PlanTables out{plugin::make_state_table(model, "plan"), plugin::make_controls_table(model, "plan_controls")};
  out.states.metadata = {{"status", planner::to_string(plan.status)},
                         {"success", plan.status == planner::SolveStatus::Solved ? "true" : "false"},
                         {"objective", format(plan.sos.effort_value)},
                         {"solver_duration", format(plan.setup_seconds + plan.solve_seconds)}};
  for (const auto& src : times_from.rows) {
    const double time = std::min(src[0], plan.path.duration_s);
    const planner::Jet qj = plan.jointJet(time);
    const planner::MusclePoint mp = flat.inverse(qj, plan.flatOutputJet(time));
    std::vector<double> row = {src[0]}, controls = {src[0]};
    for (int i = 0; i < model.numJoints(); ++i) row.push_back(qj(i, 0)), row.push_back(qj(i, 1));
    for (int j = 0; j < model.numMuscles(); ++j) {
      row.push_back(mp.activation[j]);
      row.push_back(mp.tendon_length_m[j]);
      row.push_back(mp.tendon_force_N[j]);
      row.push_back(mp.fiber_length_m[j]);
      row.push_back(-mp.shortening_velocity_m_per_s[j]);
      controls.push_back(mp.excitation[j]);
    }
    out.states.rows.push_back(std::move(row));
    out.controls.rows.push_back(std::move(controls));
  }
  return out;
}

Tracking compare(const plugin::MusculoskeletalModel& model, const plugin::StoTable& a, const plugin::StoTable& b) {
  Tracking e;
  auto max_diff = [&](const std::string& column) {
    const auto x = a.column(column), y = b.column(column);
    double d = 0.0;
    for (std::size_t i = 0; i < std::min(x.size(), y.size()); ++i) d = std::max(d, std::abs(x[i] - y[i]));
    return d;
  };
  for (int i = 0; i < model.numJoints(); ++i) {
    double& worst = model.description().joints[static_cast<std::size_t>(i)].isSlider() ? e.max_slider_error_m : e.max_q_error_rad;
    worst = std::max(worst, max_diff(plugin::coordinate_value_column(model, i)));
  }
  for (const auto& m : model.description().muscles) {
    const std::string base = "/forceset/" + m.parameters.name + "/";
    e.max_activation_error = std::max(e.max_activation_error, max_diff(base + "activation"));
    e.max_tendon_length_error_m = std::max(e.max_tendon_length_error_m, max_diff(base + "tendon_length"));
  }
  return e;
}

nlohmann::json problem_summary(const planner::FlatOutputMap& flat) {
  const plugin::ModelDescription& d = flat.model().description();
  const planner::FlatOutputChoice& y = flat.flatOutputs();
  nlohmann::json rows = nlohmann::json::array();
  for (int l = 0; l < flat.numFlatOutputs(); ++l) {
    nlohmann::json weights = nlohmann::json::object();
    for (int j = 0; j < flat.numMuscles(); ++j)
      if (y.E(l, j) != 0.0) weights[d.muscles[static_cast<std::size_t>(j)].parameters.name] = y.E(l, j);
    rows.push_back({{"name", y.names[static_cast<std::size_t>(l)]}, {"weights", weights}});
  }
  nlohmann::json margin = {{"value", y.margin.margin}, {"condition_number", y.margin.condition_number}};
  if (!flat.hasConstantMomentArms() && y.margin.posture_rad.size() > 0) {  // else the same everywhere
    nlohmann::json posture = nlohmann::json::object();
    for (int i = 0; i < flat.numJoints(); ++i)
      posture[d.joints[static_cast<std::size_t>(i)].name] = y.margin.posture_rad[i] * d.joints[static_cast<std::size_t>(i)].displayPerSI();
    margin["posture_deg"] = posture;  // a slider's in m
  }
  if (y.margin.muscle >= 0) margin["muscle"] = d.muscles[static_cast<std::size_t>(y.margin.muscle)].parameters.name;
  nlohmann::json effort = nlohmann::json::object();
  for (int j = 0; j < flat.numMuscles(); ++j)
    effort[d.muscles[static_cast<std::size_t>(j)].parameters.name] = flat.effortWeights()[j];
  const char* kind = "per_muscle";
  switch (flat.effortKind()) {
    case plugin::EffortWeights::Kind::Default:  // resolved by the map; never seen here
    case plugin::EffortWeights::Kind::FlatOutputs: kind = "flat_outputs"; break;
    case plugin::EffortWeights::Kind::NormalizedTendonForce: kind = "normalized_tendon_force"; break;
    case plugin::EffortWeights::Kind::PerMuscle: break;
  }
  nlohmann::json limits = nlohmann::json::object();
  for (const auto& joint : d.joints)
    if (joint.limit.enabled()) {
      const plugin::JointFieldNames& field = plugin::joint_field_names(joint.type);
      limits[joint.name] = {{joint.isSlider() ? "range_m" : "range_deg",
                             {joint.range_rad[0] * joint.displayPerSI(), joint.range_rad[1] * joint.displayPerSI()}},
                            {field.stiffness, joint.limit.stiffness_N_m_per_rad},
                            {field.transition, joint.limit.transition_rad},
                            {field.damping, joint.limit.damping_N_m_s_per_rad}};
    }
  nlohmann::json region = "joint ranges";
  if (!y.region.empty()) {
    region = nlohmann::json::object();
    for (int i = 0; i < flat.numJoints(); ++i) {
      const auto& joint = d.joints[static_cast<std::size_t>(i)];
      region[joint.name] = {y.region[static_cast<std::size_t>(i)][0] * joint.displayPerSI(),
                            y.region[static_cast<std::size_t>(i)][1] * joint.displayPerSI()};  // deg, a slider's m
    }
  }
  return {{"flat_outputs",
           {{"chosen_by", y.automatic ? "library" : "model"},
            {"rows", rows},
            {"assumption1_margin", margin},
            {"region", region}}},
          {"effort_weights", {{"kind", kind}, {"per_muscle", effort}}},
          {"joint_limits", limits}};
}

nlohmann::json shortest_transfer_summary(const planner::ShortestTransfer& search) {
  nlohmann::json tried = nlohmann::json::array();
  for (const auto& t : search.tried)
    tried.push_back({{"duration_s", t.duration_s},
                     {"status", planner::to_string(t.status)},
                     {"cost_Ns", t.cost_N_s},
                     {"message", t.message},
                     {"seconds", t.seconds}});
  return {{"status", planner::to_string(search.status)},
          {"success", search.status == planner::SolveStatus::Solved},
          {"message", search.message},
          {"shortest_duration_s", search.shortest_s},
          {"no_plan_below_s", search.no_plan_below_s},
          {"below_status", planner::to_string(search.below_status)},
          {"below_message", search.below_message},
          {"at_lower_end", search.at_lower_end},
          {"plans", search.tried.size()},
          {"seconds", search.seconds},
          {"tried", tried}};
}

nlohmann::json plan_summary(const planner::OpenLoopPlan& plan, const planner::FlatOutputMap& flat) {
  const plugin::MusculoskeletalModel& model = flat.model();
  nlohmann::json j;
  j["status"] = planner::to_string(plan.status);
  j["success"] = plan.status == planner::SolveStatus::Solved;
  j["message"] = plan.message;
  j["model"] = model.description().name;
  const auto& s = plan.sos;
  j["cost_Ns"] = s.cost_N_s;  // the name kept for readers of older summaries; the unit is cost_unit
  j["cost_unit"] = flat.effortUnit();
  j["effort"] = s.effort_name;  // what the plan minimized, its value and unit
  j["effort_value"] = s.effort_value;
  j["effort_unit"] = s.effort_unit;
  j["solve_seconds"] = plan.setup_seconds + plan.solve_seconds;
  j["setup_seconds"] = plan.setup_seconds;
  j["sos_method"] = s.method;
  // The solve's time under the name of the method that solved (as flatsos_bench names it).
  j[s.method == "exchange" ? "exchange_solve_seconds" : "whole_program_nlp_solve_seconds"] =
      plan.solve_seconds;
  j["certify_seconds"] = plan.certify_seconds;
  j["check_seconds"] = plan.check_seconds;
  j["ipopt_iterations"] = s.ipopt_iterations;
  j["ipopt_calls"] = s.ipopt_calls;
  // Which linear solver factored those calls' KKT systems: flatsos's dense LDL^T or MUMPS.
  j["ipopt_linear_solver"] = s.ipopt_linear_solver;
  j["exchange_rounds"] = s.exchange_rounds;
  if (s.method == "whole_program_nlp")
    j["whole_program_nlp"] = {{"variables", s.nlp_variables},
                              {"equalities", s.nlp_equalities},
                              {"max_certificate_residual_N", s.max_certificate_residual_N}};
  j["lp_points"] = s.lp_points;
  j["flat_output_basis"] = {
      {"degree", plan.flat_output_degree}, {"spans", plan.flat_output_spans}, {"span_growth", plan.flat_output_span_growth}};
  std::vector<double> piece_starts_s;
  for (const auto& piece : plan.torque.pieces) piece_starts_s.push_back(piece.t0_s);
  j["torque_model"] = {{"pieces", plan.torque.pieces.size()},
                       {"piece_starts_s", piece_starts_s},
                       {"degree", plan.torque.pieces.empty() || plan.torque.pieces[0].torque.empty() ? 0 : plan.torque.pieces[0].torque[0].degree()}};
  j["certificates"] = {{"near_active_pieces", s.near_active_pieces}, {"certified_pieces", s.certified_pieces}, {"all_certified", s.certified}};
  j["excitation_bounds"] = {{"imposed", s.bounds_imposed},
                            {"rounds", s.bound_rounds},
                            {"points", s.bound_points},
                            {"sequential_lp_iterations", s.bound_sequential_lp_iterations},
                            {"max_excess_on_check_grid", s.max_bound_excess},
                            {"seconds", s.bounds_seconds}};
  nlohmann::json qc = nlohmann::json::object();
  if (plan.path.spline) {
    // An optimized path: clamped B-spline coefficients, as the flat outputs'.
    for (int i = 0; i < plan.path.numJoints(); ++i) {
      const Eigen::VectorXd c = plan.path.spline->coefficients().row(i).transpose();
      qc[model.description().joints[static_cast<std::size_t>(i)].name] = std::vector<double>(c.data(), c.data() + c.size());
    }
    const planner::BSplineBasis& basis = plan.path.spline->basis();
    j["q_coefficient_convention"] = "clamped B-spline on [0, T] with interior knots at q_breakpoints_s, rad; degree " +
                                    std::to_string(basis.degree()) + ", " + std::to_string(basis.spans()) + " spans";
    j["q_breakpoints_s"] = basis.breakpoints();
  } else {
    for (std::size_t i = 0; i < plan.path.q.size(); ++i) {
      const auto& c = plan.path.q[i].coefficients();
      qc[model.description().joints[i].name] = std::vector<double>(c.data(), c.data() + c.size());
    }
    j["q_coefficient_convention"] = "ascending powers of t in seconds, rad";
  }
  j["q_coeffs"] = qc;
  const planner::FreePathReport& f = plan.free_path;
  if (f.optimized || !f.prescribed_status.empty()) {
    const bool newton = f.method == planner::FreePathMethod::JointNewton;
    j["free_path"] = {{"optimized", f.optimized},
                      {"method", planner::to_string(f.method)},
                      {"prescribed_path_status", f.prescribed_status},
                      {"prescribed_path_cost_Ns", f.prescribed_cost_N_s},
                      {"start_flat_output_spans", f.start_flat_output_spans},
                      {"cost_at_points_Ns", f.cost_at_points_N_s},
                      {"rounds", f.rounds},
                      {"points", f.points},
                      {newton ? "ipopt_iterations" : "quasi_newton_steps", f.path_iterations},
                      {"final_torque_pieces", f.final_torque_pieces},
                      {"final_plans", f.final_plans},
                      {"seconds", f.seconds}};
    if (!newton) {
      j["free_path"]["evaluations"] = f.evaluations;
      j["free_path"]["sequential_lp_iterations"] = f.sequential_lp_iterations;
    }
  }
  if (plan.Y) {
    const planner::BSplineBasis& basis = plan.Y->basis();
    nlohmann::json yc = nlohmann::json::object();
    for (int l = 0; l < plan.Y->signals(); ++l) {
      const Eigen::VectorXd c = plan.Y->coefficients().row(l).transpose();
      yc[flat.flatOutputs().names[static_cast<std::size_t>(l)]] = std::vector<double>(c.data(), c.data() + c.size());
    }
    j["flat_outputs"] = {{"basis", "clamped B-spline on [0, T] with interior knots at breakpoints_s"},
                         {"degree", basis.degree()},
                         {"spans", basis.spans()},
                         {"breakpoints_s", basis.breakpoints()},
                         {"duration_s", basis.duration()},
                         {"coefficients_N", yc}};
  }
  if (plan.status == planner::SolveStatus::Solved) {
    j["check_points"] = plan.check.points;
    j["min_tendon_force_N"] = plan.check.min_tendon_force_N;
    j["min_reserve_margin_N"] = plan.check.min_reserve_margin_N;
    j["activation_range"] = {plan.check.min_activation, plan.check.max_activation};
    j["excitation_range"] = {plan.check.min_excitation, plan.check.max_excitation};
    j["points_outside_domain"] = plan.check.points_outside_domain;
  }
  return j;
}

std::vector<std::string> print_warnings(const char* program, const std::vector<std::string>& first,
                                        const std::vector<std::string>& second) {
  std::vector<std::string> all = first;
  all.insert(all.end(), second.begin(), second.end());
  for (const auto& w : second) std::cerr << program << ": warning: " << w << "\n";
  return all;
}

void write_json(const std::string& path, const nlohmann::json& j) { plugin::write_file_atomically(path, j.dump(2) + "\n"); }

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

namespace {

// The model's plausibility warnings, printed as soon as it is loaded: a failure later (a rest
// state the SLP cannot find for a 1500 kg body) must not hide them.
std::shared_ptr<const plugin::MusculoskeletalModel> with_warnings_printed(
    std::shared_ptr<const plugin::MusculoskeletalModel> model, const std::string& program) {
  for (const auto& w : model->warnings()) std::cerr << program << ": warning: " << w << "\n";
  return model;
}

}  // namespace

std::shared_ptr<const plugin::MusculoskeletalModel> load_model(const std::string& path, const std::string& program,
                                                               const OpenSimModelOptions& options) {
  const bool osim = plugin::is_opensim_model_file(path);
  const char* osim_only = options.opensim_2_muscles           ? "--opensim-2-muscles"
                          : options.degroote_muscles            ? "--degroote-muscles"
                          : options.ignore_passive_fiber_forces ? "--ignore-passive-fiber-forces"
                          : options.paths == "geometry"         ? "--paths geometry"
                                                                : nullptr;
  if (!osim && osim_only)
    throw std::invalid_argument(std::string(osim_only) + ": the model must be an OpenSim model (.osim), not '" + path + "'");
  if (!osim) return with_warnings_printed(plugin::MusculoskeletalModel::fromFile(path), program);
  plugin::OpenSimFileOptions file_options;
  file_options.simulate_geometry = options.paths == "geometry";
  file_options.opensim_2_muscles = options.opensim_2_muscles;
  file_options.degroote_fregly2016_muscles = options.degroote_muscles;
  file_options.ignore_passive_fiber_forces = options.ignore_passive_fiber_forces;
  const plugin::OpenSimImport imported = plugin::import_opensim_file(path, file_options);
  std::cout << program << ": imported " << path << ": " << imported.model.numJoints() << " joint(s), "
            << imported.model.numMuscles() << " muscles\n";
  for (const std::string& note : imported.notes) std::cout << "  " << note << "\n";
  return with_warnings_printed(std::make_shared<const plugin::MusculoskeletalModel>(imported.model), program);
}

void add_opensim_model_options(CLI::App& app, OpenSimModelOptions& osim) {
  app.add_option("--paths", osim.paths,
                 "muscle paths in simulation: fitted (the polynomials the plans use) or geometry (an .osim's "
                 "GeometryPaths with via points and wrapping, as OpenSim simulates them)")
      ->capture_default_str()
      ->check(CLI::IsMember({"fitted", "geometry"}));
  CLI::Option* opensim_2 = app.add_flag("--opensim-2-muscles", osim.opensim_2_muscles,
                                        "an .osim's Thelen2003Muscles, and its cylinder wrapping, as OpenSim 2.x "
                                        "modelled them (to reproduce results of that time; OpenSim 4's otherwise)");
  add_degroote_options(app, osim, opensim_2);
}

void add_degroote_options(CLI::App& app, OpenSimModelOptions& osim, CLI::Option* opensim_2_muscles) {
  CLI::Option* degroote = app.add_flag("--degroote-muscles", osim.degroote_muscles,
                                       "every muscle of an .osim replaced by a DeGrooteFregly2016Muscle as OpenSim Moco's "
                                       "ModOpReplaceMusclesWithDeGrooteFregly2016 does (smooth laws, as MocoInverse uses)");
  degroote->excludes(opensim_2_muscles);
  app.add_flag("--ignore-passive-fiber-forces", osim.ignore_passive_fiber_forces,
               "with --degroote-muscles: their passive fibre force left out (Moco's ModOpIgnorePassiveFiberForcesDGF)")
      ->needs(degroote);
}

}  // namespace flatsos::examples
