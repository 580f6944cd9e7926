// opensim_to_model: a flatsos model (JSON) from an OpenSim model (.osim), its muscle paths fitted
// to the model's GeometryPaths or read from a FunctionBasedPathSet (OpenSim 4.5+): kept
// coordinates become pin or slider joints, the others are held; see plugin/io/opensim_import.hpp.
#include <CLI/CLI.hpp>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "example_support.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"
#include "flatsos/plugin/io/sto_file.hpp"
#include "programs.hpp"

namespace flatsos::programs::opensim_to_model {

namespace fp = flatsos::plugin;
namespace ex = flatsos::examples;

namespace {

// "name=value" -> (name, value); CLI::ValidationError naming the option otherwise.
std::pair<std::string, std::string> split_assignment(const std::string& text, const std::string& option) {
  const std::size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size())
    throw CLI::ValidationError(option, "'" + text + "' is not COORD=VALUE");
  return {text.substr(0, eq), text.substr(eq + 1)};
}

double number(const std::string& text, const std::string& option) {
  std::size_t used = 0;
  double v = NAN;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(v)) throw CLI::ValidationError(option, "'" + text + "' is not a finite number");
  return v;
}

}  // namespace

int run(int argc, char** argv) {
  CLI::App app{"A flatsos model from an OpenSim model (.osim).\n"
               "Muscle lengths are polynomials of the kept coordinates fitted to the model's GeometryPaths (via points, "
               "wrapping) over the kept ranges, as OpenSim's PolynomialPathFitter fits them, each muscle's error reported; "
               "--paths uses a FunctionBasedPathSet instead.\n"
               "The pelvis (the root body) is welded to ground; every kept coordinate becomes a pin joint about its OpenSim axis (exact for a joint that is one rotation), "
               "with OpenSim's name, sign and range; every other coordinate is held at its --hold value or 0, in the "
               "kinematics and inside the path polynomials (a coordinate coupled to another follows it). Bodies beyond a "
               "kept joint are lumped into its child body. Every muscle whose fitted length depends on a kept "
               "coordinate comes along; one whose tendon would be slack somewhere in the range is left out and reported. "
               "What was held and approximated is written to the model's \"provenance\"."};
  std::string osim, paths_file, out, name, scenarios_file;
  std::vector<std::string> keep, hold, ranges;
  bool refuse_slack = false, millard_with_flatsos_laws = false;
  app.add_option("--osim", osim, "OpenSim model file (.osim)")->required();
  app.add_option("--paths", paths_file,
                 "OpenSim FunctionBasedPathSet file (fitted muscle lengths) to use instead of fitting the model's GeometryPaths");
  app.add_option("--keep", keep,
                 "a coordinate that becomes a pin joint (a translation: a slider joint; repeat for more; at most one per joint)")
      ->required();
  app.add_option("--hold", hold, "COORD=VALUE: hold a coordinate at VALUE (deg for rotations, m for translations); repeat");
  app.add_option("--range", ranges,
                 "COORD=LOW:HIGH: the range of a kept coordinate in deg (m for translations), inside OpenSim's (keep it "
                 "where the fitted paths were fitted); repeat");
  app.add_option("--name", name, "the model's name (default: the OpenSim model's)");
  app.add_option("--scenarios", scenarios_file,
                 "a JSON object of named scenarios to include (the model file's \"scenarios\": q0_deg, target_deg, ...)");
  app.add_flag("--refuse-slack-muscles", refuse_slack, "fail instead of leaving out a muscle whose tendon would be slack");
  app.add_flag("--millard-with-flatsos-laws", millard_with_flatsos_laws,
               "give Millard2012EquilibriumMuscles flatsos' default Hill laws instead of their OpenSim curves");
  app.add_option("--out", out, "the model file to write (JSON)")->required();
  if (const int rc = ex::parse_arguments(app, argc, argv); rc >= 0) return rc;

  try {
    const fp::OpenSimModel model = fp::read_opensim_model(osim);
    fp::OpenSimImportOptions options;
    options.name = name;
    options.keep = keep;
    options.refuse_slack_muscles = refuse_slack;
    options.millard_with_flatsos_laws = millard_with_flatsos_laws;
    // File names only: a model must not point into the machine it was made on.
    options.osim_source = std::filesystem::path(osim).filename().string();
    if (!paths_file.empty()) options.paths_source = std::filesystem::path(paths_file).filename().string();
    try {
      for (const std::string& h : hold) {
        const auto [coordinate, value] = split_assignment(h, "--hold");
        const fp::OpenSimCoordinate* c = model.coordinate(coordinate);
        if (!c) throw CLI::ValidationError("--hold", "'" + coordinate + "': the OpenSim model has no such coordinate");
        if (options.hold.count(coordinate)) throw CLI::ValidationError("--hold", "'" + coordinate + "' given twice");
        options.hold[coordinate] = number(value, "--hold") * (c->rotational ? ex::kRadPerDeg : 1.0);
      }
      for (const std::string& r : ranges) {
        const auto [coordinate, value] = split_assignment(r, "--range");
        const std::size_t colon = value.find(':');
        if (colon == std::string::npos) throw CLI::ValidationError("--range", "'" + r + "' is not COORD=LOW:HIGH");
        if (options.ranges.count(coordinate)) throw CLI::ValidationError("--range", "'" + coordinate + "' given twice");
        const fp::OpenSimCoordinate* c = model.coordinate(coordinate);
        const double scale = c && !c->rotational ? 1.0 : ex::kRadPerDeg;  // an unknown one: the importer names it
        options.ranges[coordinate] = {number(value.substr(0, colon), "--range") * scale,
                                      number(value.substr(colon + 1), "--range") * scale};
      }
    } catch (const CLI::Error& e) {
      std::cerr << "opensim_to_model: " << e.what() << "\n";
      return 2;
    }
    const fp::OpenSimImport imported =
        paths_file.empty() ? fp::import_opensim_model(model, fp::read_opensim_geometry_paths(osim), options)
                           : fp::import_opensim_model(model, fp::read_opensim_function_based_paths(paths_file), options);
    nlohmann::json document = nlohmann::json::parse(fp::model_json_text(imported.model));
    if (!scenarios_file.empty()) {
      std::ifstream in(scenarios_file);
      if (!in) throw std::runtime_error("scenarios file '" + scenarios_file + "': cannot be opened");
      try {
        document["scenarios"] = nlohmann::json::parse(in);
      } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error("scenarios file '" + scenarios_file + "': not valid JSON: " + e.what());
      }
    }
    const std::string text = document.dump(2) + "\n";
    const fp::ModelDescription written = fp::parse_model_json(text, out);  // what every program will read
    fp::write_file_atomically(out, text);
    std::cout << "opensim_to_model: wrote " << out << ": " << written.numJoints() << " joint(s), " << written.numMuscles()
              << " muscles, " << written.bodies.size() << " bodies\n";
    for (const std::string& note : imported.notes) std::cout << "  " << note << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "opensim_to_model: error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace flatsos::programs::opensim_to_model
