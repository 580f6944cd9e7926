#pragma once
// Shared pieces of the example programs: argument helpers, plan tables, summaries, comparisons.

#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "flatsos/planner/motion_planner.hpp"
#include "flatsos/planner/shortest_transfer.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"
#include "flatsos/plugin/io/sto_file.hpp"

namespace flatsos::examples {

constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;

Eigen::VectorXd to_vector(const std::vector<double>& v);
/// A model's coordinates as the programs read and write them: degrees for a pin, metres for a
/// slider (OpenSim's inDegrees converts only rotations), and back to SI (rad, m). Vectors of
/// another size than the model's joints are converted as if every joint were a pin.
Eigen::VectorXd to_display(const plugin::ModelDescription& model, const Eigen::VectorXd& q_si);
Eigen::VectorXd from_display(const plugin::ModelDescription& model, const Eigen::VectorXd& q_shown);
/// Throws CLI::ValidationError unless v has n entries.
void require_count(const std::vector<double>& v, int n, const std::string& option);
/// Checks of a number option whose messages say the bound and the value given ("must be > 0 (got
/// 0)"), where CLI11's PositiveNumber printed a range ending in DBL_MAX's 309 digits.
CLI::Validator positive_number();
CLI::Validator nonnegative_number();
/// Parses the command line: -1 to go on, otherwise the exit code (0 after --help, 2 for bad
/// arguments, with CLI11's message printed).
int parse_arguments(CLI::App& app, int argc, char** argv);
/// --integrator with the names of plugin::integrator_name as its only accepted values.
CLI::Option* add_integrator_option(CLI::App& app, std::string& name, const std::string& help);
/// The programs' default for --max-integrator-steps: about a minute of Runge-Kutta-Merson, where a
/// plan's replay takes 5-10 thousand steps at 1e-10.
constexpr long kDefaultMaxIntegratorSteps = 1000000;
/// --max-integrator-steps: the simulation stops (and the program fails, saying why) after this
/// many integrator steps; 0: no limit.
CLI::Option* add_max_steps_option(CLI::App& app, long& max_steps);
/// One value for all muscles or one per muscle.
Eigen::VectorXd per_muscle(const std::vector<double>& v, int m, const std::string& option);

/// What --effort takes: planner::effort_names() and "paper" (the model's effort_weights, as
/// "tendon_force" is).
std::vector<std::string> effort_option_names();
/// Null for "paper" and "tendon_force" (the model's own linear effort), else the named effort.
std::shared_ptr<const planner::Effort> effort_option(const std::string& name);
std::string format(double x);

/// The plan evaluated at the times of `times_from` (its first column): its states with the
/// columns of plugin::make_state_table (planned q, qd and muscle states) and its controls with
/// those of plugin::make_controls_table (excitations from the inverse map, before clamping).
struct PlanTables {
  plugin::StoTable states, controls;
};
PlanTables plan_tables(const planner::FlatOutputMap& flat, const planner::OpenLoopPlan& plan,
                       const plugin::StoTable& times_from);

struct Tracking {
  double max_q_error_rad = 0.0, max_activation_error = 0.0, max_tendon_length_error_m = 0.0;
  double max_slider_error_m = 0.0;  ///< over the sliders (max_q_error_rad: over the pins)
};
/// Largest differences between two state tables with the same rows and columns.
Tracking compare(const plugin::MusculoskeletalModel& model, const plugin::StoTable& a, const plugin::StoTable& b);

/// status, cost, timings, iterations, coefficients and the a-posteriori check of a plan.
nlohmann::json plan_summary(const planner::OpenLoopPlan& plan, const planner::FlatOutputMap& flat);

/// The shortest-transfer search: its verdict, bracket and every duration it planned.
nlohmann::json shortest_transfer_summary(const planner::ShortestTransfer& search);

/// What the planner minimizes and in which coordinates: the flat outputs E (row names, who chose
/// them, Assumption 1's margin over the joint ranges, where it is smallest, the condition
/// number), the effort weights per muscle, and the joints' limit torques.
nlohmann::json problem_summary(const planner::FlatOutputMap& flat);

/// Prints the task's warnings (`second`) as "<program>: warning: <text>" on stderr and returns the
/// model's (`first`, printed by load_model when it loaded the model) and the task's, for the
/// summary's "warnings".
std::vector<std::string> print_warnings(const char* program, const std::vector<std::string>& first,
                                        const std::vector<std::string>& second = {});

/// Writes pretty JSON atomically.
void write_json(const std::string& path, const nlohmann::json& j);

double median(std::vector<double> v);

/// How a program reads an OpenSim model: which paths its simulation uses ("fitted", the
/// polynomials plans use, or "geometry", the GeometryPaths), whether its Thelen muscles are
/// OpenSim 2.x's, or every muscle DeGroote-Fregly's as OpenSim Moco replaces them (and their
/// passive force ignored).
struct OpenSimModelOptions {
  std::string paths = "fitted";
  bool opensim_2_muscles = false;
  bool degroote_muscles = false;
  bool ignore_passive_fiber_forces = false;
};
/// The model a program is given: a model file (JSON), or an OpenSim model (.osim) imported on
/// the way with its own settings, the import's notes printed. std::invalid_argument when
/// `osim` asks for what a JSON model cannot give.
std::shared_ptr<const plugin::MusculoskeletalModel> load_model(const std::string& path, const std::string& program,
                                                               const OpenSimModelOptions& osim = {});
/// Adds --paths (fitted | geometry), --opensim-2-muscles, --degroote-muscles and
/// --ignore-passive-fiber-forces to a program.
void add_opensim_model_options(CLI::App& app, OpenSimModelOptions& osim);
/// Adds --degroote-muscles (excluding the given --opensim-2-muscles) and
/// --ignore-passive-fiber-forces, for a program that words its own --opensim-2-muscles.
void add_degroote_options(CLI::App& app, OpenSimModelOptions& osim, CLI::Option* opensim_2_muscles);

}  // namespace flatsos::examples
