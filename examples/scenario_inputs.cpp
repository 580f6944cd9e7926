#include "scenario_inputs.hpp"

#include "flatsos/planner/rest_state.hpp"
#include "flatsos/planner/task_region.hpp"
#include "example_support.hpp"

namespace flatsos::examples {

namespace {

constexpr double kFallbackTargetStepDeg = 30.0;
constexpr double kFallbackTargetStepSlider_m = 0.05;

std::vector<double> as_std(const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }

// Given (size checked, each entry scaled) > the model's (already validated) > fallback; records the source.
Eigen::VectorXd pick(const std::vector<double>& given, const Eigen::VectorXd& scale, int size, const std::string& option,
                     const Eigen::VectorXd* from_model, const Eigen::VectorXd& fallback, nlohmann::json& sources,
                     const char* key) {
  if (!given.empty()) {
    if (static_cast<int>(given.size()) != size)
      throw CLI::ValidationError(option, "expects " + std::to_string(size) + " comma-separated values (the model's count), got " +
                                             std::to_string(given.size()));
    sources[key] = "command line";
    return Eigen::Map<const Eigen::VectorXd>(given.data(), size).cwiseProduct(scale);
  }
  if (from_model && from_model->size()) {
    sources[key] = "model";
    return *from_model;
  }
  sources[key] = "default";
  return fallback;
}

}  // namespace

nlohmann::json ScenarioInputs::describe() const {
  nlohmann::json j;
  j["scenario"] = scenario;
  auto shown = [&](Eigen::VectorXd v) {  // degrees, a slider's metres
    for (Eigen::Index i = 0; i < v.size(); ++i) v[i] = i < shown_per_si.size() && shown_per_si[i] == 1.0 ? v[i] : v[i] / kRadPerDeg;
    return as_std(v);
  };
  j["q0_deg"] = shown(q0_rad);
  j["qd0_deg_per_s"] = shown(qd0_rad_per_s);
  j["target_deg"] = shown(target_q_rad);
  j["duration_s"] = duration_s;
  j["reserves_N"] = as_std(reserves_N);
  j["a0"] = activations ? nlohmann::json(as_std(*activations)) : nlohmann::json("minimum-effort rest state");
  j["sources"] = sources;
  return j;
}

void add_scenario_options(CLI::App& app, ScenarioOptions& o, const std::string& scenario, bool initial_muscle_state,
                          double fallback_duration_s, double fallback_reserve_N) {
  const std::string from = " (default: the model's scenario '" + scenario + "', else ";
  app.add_option("--q0-deg", o.q0_deg, "initial joint angles, deg (a slider's in m), one per joint" + from + "0)")->delimiter(',');
  if (initial_muscle_state) {
    app.add_option("--qd0-deg-per-s", o.qd0_deg_per_s, "initial joint speeds, deg/s (a slider's in m/s), one per joint" + from + "0)")
        ->delimiter(',');
    app.add_option("--a0", o.a0,
                   "initial activations in (0, 1], one per muscle; tendons start in static equilibrium" + from +
                       "the minimum-effort rest state at q0)")
        ->delimiter(',');
  }
  app.add_option("--target-deg", o.target_deg,
                 "target joint angles, deg (a slider's in m), one per joint" + from + "q0 + " +
                     std::to_string(int(kFallbackTargetStepDeg)) + " deg, a slider's + 0.05 m)")
      ->delimiter(',');
  app.add_option("--duration-s", o.duration_s, "duration, s" + from + CLI::detail::to_string(fallback_duration_s) + ")")
      ->check(flatsos::examples::positive_number());
  app.add_option("--reserves-N", o.reserves_N,
                 "minimum tendon forces, N, one for all muscles or one per muscle" + from +
                     CLI::detail::to_string(fallback_reserve_N) + ")")
      ->delimiter(',');
}

ScenarioInputs resolve_scenario(const plugin::MusculoskeletalModel& model, const std::string& scenario,
                                const ScenarioOptions& given, double fallback_duration_s, double fallback_reserve_N) {
  const int n = model.numJoints(), m = model.numMuscles();
  const plugin::ScenarioDescription* sc = model.description().scenario(scenario);
  ScenarioInputs in;
  in.scenario = scenario;
  in.sources = nlohmann::json::object();
  in.shown_per_si.resize(n);
  Eigen::VectorXd rad_per_shown(n), fallback_step(n);
  for (int i = 0; i < n; ++i) {
    const plugin::JointDescription& joint = model.description().joints[static_cast<std::size_t>(i)];
    in.shown_per_si[i] = joint.displayPerSI();
    rad_per_shown[i] = joint.isSlider() ? 1.0 : kRadPerDeg;
    fallback_step[i] = joint.isSlider() ? kFallbackTargetStepSlider_m : kFallbackTargetStepDeg * kRadPerDeg;
  }
  in.q0_rad = pick(given.q0_deg, rad_per_shown, n, "--q0-deg", sc ? &sc->q0_rad : nullptr, Eigen::VectorXd::Zero(n), in.sources, "q0");
  in.qd0_rad_per_s = pick(given.qd0_deg_per_s, rad_per_shown, n, "--qd0-deg-per-s", sc ? &sc->qd0_rad_per_s : nullptr,
                          Eigen::VectorXd::Zero(n), in.sources, "qd0");
  in.target_q_rad = pick(given.target_deg, rad_per_shown, n, "--target-deg", sc ? &sc->target_q_rad : nullptr,
                         in.q0_rad + fallback_step, in.sources, "target");
  if (!given.a0.empty() || (sc && sc->activations.size())) {
    in.activations = pick(given.a0, Eigen::VectorXd::Ones(m), m, "--a0", sc ? &sc->activations : nullptr, Eigen::VectorXd(), in.sources, "a0");
    if (!(in.activations->minCoeff() > 0.0 && in.activations->maxCoeff() <= 1.0))
      throw CLI::ValidationError("--a0", "activations must lie in (0, 1]");
  } else {
    in.sources["a0"] = "default";
  }
  if (given.duration_s > 0.0) {
    in.duration_s = given.duration_s, in.sources["duration"] = "command line";
  } else if (sc && sc->duration_s > 0.0) {
    in.duration_s = sc->duration_s, in.sources["duration"] = "model";
  } else {
    in.duration_s = fallback_duration_s, in.sources["duration"] = "default";
  }
  // One value for all muscles or one per muscle, from either place.
  std::vector<double> reserves = given.reserves_N;
  std::string reserve_source = "command line";
  if (reserves.empty() && sc && sc->reserves_N.size()) reserves = as_std(sc->reserves_N), reserve_source = "model";
  if (reserves.empty()) reserves = {fallback_reserve_N}, reserve_source = "default";
  if (reserves.size() != 1 && static_cast<int>(reserves.size()) != m)
    throw CLI::ValidationError("--reserves-N", "expects 1 or " + std::to_string(m) + " comma-separated values, got " +
                                                   std::to_string(reserves.size()));
  for (double r : reserves)
    if (!(r >= 0.0)) throw CLI::ValidationError("--reserves-N", "reserves must be >= 0 N");
  in.reserves_N = reserves.size() == 1 ? Eigen::VectorXd::Constant(m, reserves[0])
                                       : Eigen::Map<const Eigen::VectorXd>(reserves.data(), m).eval();
  in.sources["reserves"] = reserve_source;
  return in;
}

planner::FlatOutputMap task_flat_outputs(std::shared_ptr<const plugin::MusculoskeletalModel> model,
                                         const ScenarioInputs& inputs, const std::string& program) {
  planner::FlatOutputMap flat = planner::flat_outputs_for_task(model, {inputs.q0_rad, inputs.target_q_rad});
  const plugin::JointRanges& region = flat.flatOutputs().region;
  if (!region.empty())
    std::cout << program << ": no flat outputs satisfy Assumption 1 over the joint ranges; chosen over the run's region "
              << plugin::describe_region(model->description(), region) << "\n";
  return flat;
}

SimTK::State initial_state(const planner::FlatOutputMap& flat, const ScenarioInputs& in) {
  return planner::start_state(flat, in.q0_rad, in.qd0_rad_per_s, in.activations, in.reserves_N);
}

}  // namespace flatsos::examples
