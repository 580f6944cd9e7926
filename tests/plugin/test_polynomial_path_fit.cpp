// Polynomial paths fitted to OpenSim geometry: a path whose length is a polynomial is recovered
// exactly at the lowest order that holds it; on arm26 (via points, wrap cylinders and
// ellipsoids) the fit's reported errors are what the geometry and the polynomial give at other
// postures, each muscle depends on the coordinates it crosses, and bad options are named.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "flatsos/muscles/length_polynomial.hpp"
#include "flatsos/plugin/io/opensim_model.hpp"
#include "flatsos/plugin/paths/geometry_path.hpp"
#include "flatsos/plugin/paths/path_evaluation.hpp"
#include "flatsos/plugin/paths/polynomial_path_fit.hpp"

namespace {

using namespace flatsos::plugin;
using flatsos::muscles::LengthPolynomial;

constexpr double kPi = 3.14159265358979323846;
const std::string kArm26 = std::string(FLATSOS_SOURCE_DIR) + "/models/opensim/arm26/arm26.osim";

// A model with one coordinate and a path from the origin of a body welded to ground to a point
// on ground that moves along x with the coordinate as the cubic x(q) = 0.3 + 0.1 q + 0.05 q^2 +
// c3 q^3: the path's length is that cubic (positive over q in [-1, 1]). (OpenSim counts no
// force, hence no moment arm, on a segment whose ends are on one body.)
struct CubicPath {
  OpenSimModel model;
  OpenSimGeometryPaths paths;
};

CubicPath cubic_path(double c3) {
  CubicPath out;
  OpenSimCoordinate q;
  q.name = "q";
  q.joint = "j";
  q.range = {-1.0, 1.0};
  out.model.coordinates.push_back(q);
  OpenSimBody body;
  body.name = "b";
  body.mass_kg = 1.0;
  out.model.bodies.push_back(body);
  OpenSimJoint weld;
  weld.name = "weld";
  weld.type = "WeldJoint";
  weld.parent_body = "ground";
  weld.child_body = "b";
  out.model.joints.push_back(weld);
  OpenSimPathPoint origin;
  origin.name = "origin";
  origin.body = "b";
  OpenSimPathPoint moving;
  moving.name = "moving";
  moving.kind = OpenSimPathPointKind::Moving;
  moving.body = "ground";
  moving.coordinate = "q";
  moving.moving_location = {OpenSimFunction::polynomial({c3, 0.05, 0.1, 0.3}), OpenSimFunction::constant(0.0),
                            OpenSimFunction::constant(0.0)};
  out.paths.paths.push_back({"cubic", {origin, moving}, {}});
  return out;
}

TEST(PolynomialPathFit, APolynomialLengthIsRecoveredAtTheLowestOrderThatHoldsIt) {
  for (const double c3 : {0.0, 0.02}) {
    const CubicPath cubic = cubic_path(c3);
    PathFitOptions options;
    options.ranges["q"] = {-1.0, 1.0};
    const PathFit fit = fit_polynomial_paths(cubic.model, cubic.paths, options);
    ASSERT_EQ(fit.paths.size(), 1u);
    const OpenSimPolynomialPath& path = fit.paths[0];
    const PathFitReport& report = fit.reports[0];
    EXPECT_EQ(path.coordinates, std::vector<std::string>{"q"});
    EXPECT_EQ(path.coordinate_paths, std::vector<std::string>{"/jointset/j/q"});
    EXPECT_EQ(path.force_path, "/forceset/cubic");
    // Order 2 holds the quadratic; the cubic's q^3 term (0.02) misses 1e-4 m RMS at order 2.
    const int expected_order = c3 == 0.0 ? 2 : 3;
    ASSERT_EQ(path.order, expected_order) << "c3 = " << c3;
    const std::vector<double> expected = c3 == 0.0 ? std::vector<double>{0.3, 0.1, 0.05}
                                                   : std::vector<double>{0.3, 0.1, 0.05, c3};
    ASSERT_EQ(path.coefficients.size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_NEAR(path.coefficients[i], expected[i], 1e-12) << i;
    EXPECT_TRUE(report.tolerances_met);
    EXPECT_LT(report.length_max_m, 1e-12);
    EXPECT_LT(report.moment_arm_max_m, 1e-12);
  }
}

TEST(PolynomialPathFit, Arm26FitsReportTheirErrorsAndFollowTheCoordinatesTheMusclesCross) {
  const OpenSimModel model = read_opensim_model(kArm26);
  const OpenSimGeometryPaths geometry = read_opensim_geometry_paths(kArm26);
  PathFitOptions options;
  options.ranges["r_shoulder_elev"] = {-10 * kPi / 180, 60 * kPi / 180};
  options.ranges["r_elbow_flex"] = {10 * kPi / 180, 120 * kPi / 180};
  const PathFit fit = fit_polynomial_paths(model, geometry, options);
  ASSERT_EQ(fit.paths.size(), 6u);

  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (std::size_t m = 0; m < fit.paths.size(); ++m) {
    const OpenSimPolynomialPath& path = fit.paths[m];
    const PathFitReport& report = fit.reports[m];
    const std::string& muscle = path.muscle;
    // The muscles from the humerus (BRA, TRIlat, TRImed) follow the elbow only; those from the
    // scapula (TRIlong, BIClong, BICshort) both coordinates.
    const bool one_joint = muscle == "BRA" || muscle == "TRIlat" || muscle == "TRImed";
    EXPECT_EQ(path.coordinates.size(), one_joint ? 1u : 2u) << muscle;
    EXPECT_EQ(path.coordinates.back(), "r_elbow_flex") << muscle;
    EXPECT_GE(path.order, options.min_order);
    EXPECT_LE(path.order, options.max_order);

    // The report's largest length error bounds what the polynomial and the geometry give at
    // random postures (up to the check grid's resolution: 1.5 times).
    const GeometryPathEvaluator geometric(model, geometry, muscle);
    const LengthPolynomial polynomial(static_cast<int>(path.coordinates.size()), path.order, path.coefficients);
    double worst = 0.0;
    for (int i = 0; i < 200; ++i) {
      OpenSimCoordinateValues q;
      std::vector<double> x;
      for (const auto& [name, range] : options.ranges) q[name] = range[0] + unit(random) * (range[1] - range[0]);
      for (const std::string& c : path.coordinates) x.push_back(q.at(c));
      worst = std::max(worst, std::abs(polynomial.value(x.data()) - geometric.length(q)));
    }
    EXPECT_LE(worst, 1.5 * report.length_max_m + 1e-9) << muscle;
    EXPECT_GT(report.length_max_m, 0.0) << muscle;
    EXPECT_EQ(report.worst_length_posture.size(), path.coordinates.size()) << muscle;
    RecordProperty(muscle + "_length_max_mm", std::to_string(1e3 * report.length_max_m));
    RecordProperty(muscle + "_moment_arm_max_mm", std::to_string(1e3 * report.moment_arm_max_m));
  }
}

TEST(PolynomialPathFit, BadOptionsAreNamed) {
  const CubicPath cubic = cubic_path(0.0);
  auto message = [&](const PathFitOptions& options) {
    try {
      fit_polynomial_paths(cubic.model, cubic.paths, options);
    } catch (const OpenSimModelError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  PathFitOptions unknown;
  unknown.ranges["knee"] = {0.0, 1.0};
  EXPECT_NE(message(unknown).find("'knee'"), std::string::npos) << message(unknown);
  PathFitOptions reversed;
  reversed.ranges["q"] = {1.0, -1.0};
  EXPECT_NE(message(reversed).find("ranges['q']"), std::string::npos) << message(reversed);
  PathFitOptions orders;
  orders.ranges["q"] = {-1.0, 1.0};
  orders.min_order = 5;
  orders.max_order = 3;
  EXPECT_NE(message(orders).find("min_order"), std::string::npos) << message(orders);
}

}  // namespace
