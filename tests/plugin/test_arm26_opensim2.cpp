// OpenSim's arm26 tutorial forward simulation (written in 2011 by OpenSim 2.x), reproduced from
// arm26.osim as distributed: its GeometryPaths (via points, wrap cylinders and ellipsoids) and
// its Thelen muscles as OpenSim 2.x modelled them. First the paths alone: the musculotendon
// length each row of OpenSim's states implies (its fibre length along the tendon plus the tendon
// length its force balance gives) against flatsos' geometric length at the row's posture; then
// the whole simulation from OpenSim's first state under the tutorial's controls.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "flatsos/muscles/thelen2003_opensim2_muscle.hpp"
#include "flatsos/plugin/integration/forward_simulation.hpp"
#include "flatsos/plugin/io/excitation_file.hpp"
#include "flatsos/plugin/io/initial_states.hpp"
#include "flatsos/plugin/io/opensim_import.hpp"
#include "flatsos/plugin/io/sto_file.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"
#include "flatsos/plugin/paths/path_evaluation.hpp"

namespace {

using namespace flatsos::plugin;
namespace fm = flatsos::muscles;

const std::string kArm26 = std::string(FLATSOS_SOURCE_DIR) + "/models/opensim/arm26/";
constexpr double kPi = 3.14159265358979323846;

// The fibre force A = F / cos - Phi_P whose shortening velocity is u under the model's own law
// (the law decreases in A): bisection.
double fiber_force_for_velocity(const fm::MuscleParameters& p, double a, double fiber_length_m, double u) {
  double lo = -2.0 * p.max_isometric_force_N, hi = 4.0 * p.max_isometric_force_N;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (p.model->ownFiberVelocity(p, a, fiber_length_m, mid).shortening_m_per_s > u ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

OpenSimCoordinateValues posture(const StoTable& states, std::size_t row) {
  return {{"r_shoulder_elev", states.rows[row][1]}, {"r_elbow_flex", states.rows[row][2]}};
}

// TRIlong's path jumps while the arm passes shoulder -16.5, elbow 84.9 deg (its wrap switches
// sides and back): OpenSim's states show its fibre taking up 8.5 mm at 0.84542 s, giving it back
// from 0.85036 s and settling by 0.8625 s. A row in that window is not compared: its fibre's speed
// cannot be read from rows that far apart for so fast a change.
bool in_trilong_jump(const std::string& muscle, double t) { return muscle == "TRIlong" && t >= 0.8454 && t <= 0.8625; }

TEST(Arm26OpenSim2, GeometricLengthsMatchTheLengthsOpenSimsStatesImply) {
  OpenSimImportOptions options;
  options.keep = {"r_shoulder_elev", "r_elbow_flex"};
  options.opensim_2_muscles = true;
  const std::string osim_file = kArm26 + "arm26.osim";
  const OpenSimModel osim = read_opensim_model(osim_file);
  OpenSimGeometryPaths geometry = read_opensim_geometry_paths(osim_file);
  geometry.opensim_2_wrapping = true;
  const ModelDescription model = import_opensim_model(osim, geometry, options).model;
  const StoTable states = read_sto(kArm26 + "forward_dynamics/arm26_states.sto");
  const auto time = states.column("time");
  for (const MuscleDescription& muscle : model.muscles) {
    const fm::MuscleParameters& p = muscle.parameters;
    ASSERT_EQ(p.model->name(), fm::Thelen2003OpenSim2Muscle::kName);
    const GeometryPathEvaluator path(osim, geometry, p.name);
    const auto activation = states.column(p.name + ".activation");
    const auto fiber = states.column(p.name + ".fiber_length");
    double worst_m = 0.0, worst_t = 0.0;
    int jump_rows = 0;
    for (std::size_t r = 1; r + 1 < time.size(); ++r) {
      // dl/dt at row r: the derivative of the parabola through rows r - 1, r, r + 1.
      const double h0 = time[r] - time[r - 1], h1 = time[r + 1] - time[r];
      const double lengthening = (-h1 / (h0 * (h0 + h1))) * fiber[r - 1] + ((h1 - h0) / (h0 * h1)) * fiber[r] +
                                 (h0 / (h1 * (h0 + h1))) * fiber[r + 1];
      const double thickness = p.optimal_fiber_length_m * std::sin(p.pennation_angle_at_optimal_rad);
      const double along = std::sqrt(fiber[r] * fiber[r] - thickness * thickness), cos_pennation = along / fiber[r];
      const double force_along_fiber =
          fiber_force_for_velocity(p, activation[r], fiber[r], -lengthening) + p.model->passiveFiberForce(p, fiber[r]).value;
      const double implied_m = p.model->tendonLengthFromForce(p, force_along_fiber * cos_pennation) + along;
      if (in_trilong_jump(p.name, time[r])) {
        ++jump_rows;
        continue;
      }
      const double geometric_m = path.length(posture(states, r));
      if (std::abs(geometric_m - implied_m) > worst_m) worst_m = std::abs(geometric_m - implied_m), worst_t = time[r];
    }
    std::printf("%-9s worst |geometric - implied| length %.4f mm at t = %.3f s (%d rows at a jump left out)\n",
                p.name.c_str(), 1e3 * worst_m, worst_t, jump_rows);
    EXPECT_LT(worst_m, 0.05e-3) << p.name << " at t = " << worst_t;  // the task's 0.05 mm
    // BRA's single cylinder wrap, with its tangent points adjusted as OpenSim 2.x did: 0.006 mm
    // (OpenSim 4's wrapping, which skips the adjustment on a path with one wrap: 0.024 mm).
    if (p.name == "BRA") {
      EXPECT_LT(worst_m, 0.01e-3);
    }
  }
}

struct Agreement {
  double coordinates_deg = 0.0, activations = 0.0;
  double worst_coordinate_t = 0.0;
};

// OpenSim's states (linearly between its rows, a few milliseconds apart) against a simulation's
// rows.
Agreement agreement_with_opensim(const MusculoskeletalModel& model, const StoTable& ours, const StoTable& opensim) {
  const auto t_os = opensim.column("time");
  const auto value_at = [&](const std::string& column, double t) {
    const auto v = opensim.column(column);
    std::size_t k = 1;
    while (k + 1 < t_os.size() && t_os[k] < t) ++k;
    const double w = (t - t_os[k - 1]) / (t_os[k] - t_os[k - 1]);
    return v[k - 1] + w * (v[k] - v[k - 1]);
  };
  Agreement a;
  for (std::size_t r = 0; r < ours.rows.size(); ++r) {
    const double t = ours.rows[r][0];
    for (const JointDescription& joint : model.description().joints) {
      const std::string c = joint.coordinateName();
      const double ours_rad = ours.rows[r][static_cast<std::size_t>(ours.columnIndex("/jointset/" + joint.name + "/" + c + "/value"))];
      const double error_deg = std::abs(ours_rad - value_at(c, t)) * 180.0 / kPi;
      if (error_deg > a.coordinates_deg) a.coordinates_deg = error_deg, a.worst_coordinate_t = t;
    }
    for (const MuscleDescription& m : model.description().muscles) {
      const std::string& name = m.parameters.name;
      const double ours_a = ours.rows[r][static_cast<std::size_t>(ours.columnIndex("/forceset/" + name + "/activation"))];
      a.activations = std::max(a.activations, std::abs(ours_a - value_at(name + ".activation", t)));
    }
  }
  return a;
}

Agreement simulate_tutorial(bool geometry, bool opensim_2_muscles) {
  const auto model = std::make_shared<const MusculoskeletalModel>(
      import_opensim_file(kArm26 + "arm26.osim", geometry, opensim_2_muscles).model);
  SimTK::State s = model->defaultState();
  model->setActivations(s, Eigen::VectorXd::Constant(model->numMuscles(), 0.01));  // when a file lacks them
  const StoTable opensim = read_sto(kArm26 + "forward_dynamics/arm26_states.sto");
  EXPECT_TRUE(set_initial_states(*model, s, opensim, "arm26_states.sto").empty());
  // OpenSim's forward tool interpolated the static optimization's activations linearly.
  std::vector<std::string> names;
  for (const auto& m : model->description().muscles) names.push_back(m.parameters.name);
  const auto controls = read_excitation_file(kArm26 + "static_optimization/arm26_StaticOptimization_activation.sto", names);
  for (int j = 0; j < model->numMuscles(); ++j) model->muscle(j).setExcitationSignal(s, controls[static_cast<std::size_t>(j)]);
  SimulationOptions options;
  options.report_interval_s = 0.002;
  const SimulationResult result = simulate(*model, s, options);
  EXPECT_TRUE(result.completed()) << result.message;
  return agreement_with_opensim(*model, result.states, opensim);
}

// OpenSim 2.x's muscles on the geometric paths, wrapped as OpenSim 2.x wrapped them, follow
// OpenSim's run: coordinates to 0.022 deg, activations to 6e-5. (With OpenSim 4's wrapping BRA
// is 0.02 mm longer below 30 deg of elbow flexion, a few newtons of tendon force on a light
// forearm, and the coordinates drift 0.23 deg.) Today's Thelen muscles on the fitted paths,
// reported beside it, end far from OpenSim's run.
TEST(Arm26OpenSim2, TheTutorialsForwardSimulationIsReproducedWithOpenSim2MusclesAndGeometricPaths) {
  const Agreement opensim2 = simulate_tutorial(true, true);
  std::printf("OpenSim 2.x muscles, geometric paths: coordinates within %.4f deg (worst at %.3f s), activations %.2g\n",
              opensim2.coordinates_deg, opensim2.worst_coordinate_t, opensim2.activations);
  const Agreement today = simulate_tutorial(false, false);
  std::printf("OpenSim 4 Thelen muscles, fitted paths: coordinates within %.2f deg, activations %.2g\n",
              today.coordinates_deg, today.activations);
  RecordProperty("opensim2_geometry_coordinates_deg", std::to_string(opensim2.coordinates_deg));
  RecordProperty("opensim4_fitted_coordinates_deg", std::to_string(today.coordinates_deg));
  EXPECT_LT(opensim2.activations, 5e-4);  // the task's bound
  EXPECT_LT(opensim2.coordinates_deg, 0.05);  // the task's bound
  EXPECT_GT(today.coordinates_deg, 10 * opensim2.coordinates_deg);  // the model, not the integration, decides
}

}  // namespace
