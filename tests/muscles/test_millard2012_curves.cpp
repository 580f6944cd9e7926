// Millard et al. (2013) muscle curves as OpenSim builds them: control points and values against
// an independent Bernstein-form evaluation of the published construction
// (millard2012_reference.hpp), anchor values and slopes from the properties, finite-difference
// twins of the first three derivatives, C2 joints, and inverse round trips.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "finite_difference.hpp"
#include "flatsos/muscles/millard2012_curves.hpp"
#include "millard2012_reference.hpp"

namespace fm = flatsos::muscles;
namespace ref = millard_reference;
using flatsos::test::central_difference;
using flatsos::test::default_step;

namespace {

const double kCos85 = std::cos(85.0 * 3.14159265358979323846 / 180.0);

struct CurveCase {
  std::string name;
  fm::QuinticBezierCurve curve;
  std::vector<ref::ControlPoints> reference;
};

std::vector<ref::ControlPoints> swapped(std::vector<ref::ControlPoints> segments) {
  for (auto& s : segments) std::swap(s.x, s.y);
  return segments;
}

fm::Millard2012CurveParameters tug_of_war() {  // models/opensim/Tug_of_War_Millard.osim
  fm::Millard2012CurveParameters p;
  p.active_force_length.transition_norm_fiber_length = 0.6259;
  p.active_force_length.minimum_value = 0.0;
  p.fiber_force_length.strain_at_one_norm_force = 0.6;
  return p;
}

// Every curve with OpenSim's defaults, typed here from its source, plus the Tug-of-War muscles.
std::vector<CurveCase> cases() {
  const fm::Millard2012CurveParameters d;
  const auto fv_inverse_properties = fm::force_velocity_inverse_curve_defaults();
  const fm::Millard2012CurveParameters tug = tug_of_war();
  return {
      {"active force-length", fm::active_force_length_curve(d.active_force_length),
       ref::active_force_length(0.47 - 0.0259, 0.73, 1.8123, 0.8616, 0.1)},
      {"force-velocity", fm::force_velocity_curve(d.force_velocity),
       ref::force_velocity(0.0, 0.25, 5.0, 0.0, 0.15, 1.4, 0.6, 0.9)},
      {"force-velocity inverse", fm::force_velocity_inverse_curve(fv_inverse_properties),
       swapped(ref::force_velocity(0.1, 0.25, 5.0, 0.1, 0.15, 1.4, 0.6, 0.9))},
      {"fiber force-length", fm::fiber_force_length_curve(d.fiber_force_length),
       ref::fiber_force_length(0.0, 0.7, 0.2, 2.0 / 0.7, 0.75)},
      {"tendon force-length", fm::tendon_force_length_curve(d.tendon_force_length),
       ref::tendon_force_length(0.049, 1.375 / 0.049, 2.0 / 3.0, 0.5)},
      {"fiber compressive force-length",
       fm::fiber_compressive_force_length_curve(d.fiber_compressive_force_length),
       ref::compressive(0.5, -4.0, 0.5)},
      {"fiber compressive force-cos-pennation",
       fm::fiber_compressive_force_cos_pennation_curve(d.fiber_compressive_force_cos_pennation),
       ref::compressive(kCos85, -2.0 / kCos85, 0.1)},
      {"Tug of War active force-length", fm::active_force_length_curve(tug.active_force_length),
       ref::active_force_length(0.4441, 0.6259, 1.8123, 0.8616, 0.0)},
      {"Tug of War fiber force-length", fm::fiber_force_length_curve(tug.fiber_force_length),
       ref::fiber_force_length(0.0, 0.6, 0.2, 2.0 / 0.6, 0.75)},
  };
}

double largest_abs(const std::vector<ref::ControlPoints>& segments, bool y) {
  double m = 0.0;
  for (const auto& s : segments)
    for (double v : (y ? s.y : s.x)) m = std::max(m, std::abs(v));
  return m;
}

struct InteriorPoint {
  double x, segment_width;
};

/// Points inside each segment, kept `margin` (a fraction of its width) from its ends.
std::vector<InteriorPoint> interior_points(const fm::QuinticBezierCurve& curve, int per_segment,
                                           double margin) {
  std::vector<InteriorPoint> points;
  for (const auto& s : curve.segments()) {
    const double width = s.x[5] - s.x[0];
    for (int i = 0; i < per_segment; ++i)
      points.push_back(
          {s.x[0] + width * (margin + (1 - 2 * margin) * i / (per_segment - 1)), width});
  }
  return points;
}

}  // namespace

TEST(Millard2012Curves, ControlPointsAreThePublishedOnes) {
  for (const auto& c : cases()) {
    ASSERT_EQ(c.curve.segments().size(), c.reference.size()) << c.name;
    const double scale_x = largest_abs(c.reference, false),
                 scale_y = largest_abs(c.reference, true);
    for (std::size_t s = 0; s < c.reference.size(); ++s)
      for (int i = 0; i < 6; ++i) {
        EXPECT_NEAR(c.curve.segments()[s].x[i], c.reference[s].x[i], 1e-12 * scale_x)
            << c.name << " " << s << " " << i;
        EXPECT_NEAR(c.curve.segments()[s].y[i], c.reference[s].y[i], 1e-12 * scale_y)
            << c.name << " " << s << " " << i;
      }
  }
}

TEST(Millard2012Curves, ValuesAndSlopesMatchBernsteinFormAtAThousandPoints) {
  for (const auto& c : cases()) {
    const int per_segment = 1000 / int(c.reference.size());
    const double scale_y = largest_abs(c.reference, true);
    std::vector<double> xs, ys, slopes;
    for (const auto& s : c.reference)
      for (int k = 0; k < per_segment; ++k) {
        const double u = double(k) / (per_segment - 1);
        xs.push_back(ref::bernstein(s.x, u));
        ys.push_back(ref::bernstein(s.y, u));
        slopes.push_back(ref::bernstein_derivative(s.y, u) / ref::bernstein_derivative(s.x, u));
      }
    double scale_slope = 0.0;
    for (double m : slopes) scale_slope = std::max(scale_slope, std::abs(m));
    double worst_value = 0.0, worst_slope = 0.0;
    for (std::size_t k = 0; k < xs.size(); ++k) {
      const fm::BezierCurveJet jet = c.curve.evaluate(xs[k]);
      worst_value = std::max(worst_value, std::abs(jet.value - ys[k]) / scale_y);
      worst_slope = std::max(worst_slope, std::abs(jet.first - slopes[k]) / scale_slope);
    }
    EXPECT_LT(worst_value, 1e-9) << c.name;
    EXPECT_LT(worst_slope, 1e-9) << c.name;
    // Beyond the ends: the straight line with the end's value and slope.
    const auto& first = c.reference.front();
    const auto& last = c.reference.back();
    const double slope0 = (first.y[1] - first.y[0]) / (first.x[1] - first.x[0]);
    const double slope1 = (last.y[5] - last.y[4]) / (last.x[5] - last.x[4]);
    const double reach = 0.5 * (last.x[5] - first.x[0]);
    const fm::BezierCurveJet before = c.curve.evaluate(first.x[0] - reach);
    const fm::BezierCurveJet after = c.curve.evaluate(last.x[5] + reach);
    EXPECT_NEAR(before.value, first.y[0] - slope0 * reach, 1e-12 * scale_y) << c.name;
    EXPECT_NEAR(after.value, last.y[5] + slope1 * reach, 1e-12 * scale_y) << c.name;
    EXPECT_NEAR(before.first, slope0, 1e-12 * scale_slope) << c.name;
    EXPECT_EQ(before.second, 0.0);
    EXPECT_EQ(after.third, 0.0);
  }
}

TEST(Millard2012Curves, AnchorValuesAndSlopesAreTheStatedProperties) {
  const fm::Millard2012CurveParameters d;
  const auto fal = fm::active_force_length_curve(d.active_force_length);
  EXPECT_NEAR(fal.value(1.0), 1.0, 1e-14);
  EXPECT_NEAR(fal.evaluate(1.0).first, 0.0, 1e-12);
  EXPECT_NEAR(fal.value(0.47 - 0.0259), 0.1, 1e-14);
  EXPECT_NEAR(fal.value(1.8123), 0.1, 1e-14);
  EXPECT_EQ(fal.value(0.2), 0.1);
  EXPECT_EQ(fal.value(2.5), 0.1);
  EXPECT_NEAR(fal.evaluate(0.73 + 0.5 * (0.95 - 0.73)).first, 0.8616, 1e-10);  // mid shallow limb

  // OpenSim's force-velocity takes the normalised LENGTHENING velocity: -1 is the fastest
  // shortening.
  const auto fv = fm::force_velocity_curve(d.force_velocity);
  EXPECT_NEAR(fv.value(0.0), 1.0, 1e-14);
  EXPECT_NEAR(fv.value(-1.0), 0.0, 1e-14);
  EXPECT_NEAR(fv.value(1.0), 1.4, 1e-14);
  EXPECT_NEAR(fv.evaluate(0.0).first, 5.0, 1e-10);
  EXPECT_NEAR(fv.evaluate(-0.9).first, 0.25, 1e-10);
  EXPECT_NEAR(fv.evaluate(0.9).first, 0.15, 1e-10);
  EXPECT_NEAR(fv.evaluate(-1.0).first, 0.0, 1e-10);
  EXPECT_NEAR(fv.evaluate(1.0).first, 0.0, 1e-10);
  EXPECT_LT(fv.value(-0.5), 1.0);

  const auto tendon = fm::tendon_force_length_curve(d.tendon_force_length);
  EXPECT_EQ(tendon.value(1.0), 0.0);
  EXPECT_EQ(tendon.value(0.97), 0.0);
  EXPECT_NEAR(tendon.value(1.049), 1.0, 1e-13);
  EXPECT_NEAR(tendon.evaluate(1.049).first, 1.375 / 0.049, 1e-10);
  EXPECT_NEAR(tendon.value(1.049 - (1.0 / 3.0) / (1.375 / 0.049)), 2.0 / 3.0,
              1e-13);  // end of the toe

  for (const double e1 : {0.7, 0.6}) {
    fm::FiberForceLengthCurveProperties p;
    p.strain_at_one_norm_force = e1;
    const auto passive = fm::fiber_force_length_curve(p);
    EXPECT_EQ(passive.value(1.0), 0.0);
    EXPECT_EQ(passive.value(0.8), 0.0);
    EXPECT_NEAR(passive.evaluate(1.0).first, 0.0, 1e-14);
    EXPECT_NEAR(passive.value(1.0 + e1), 1.0, 1e-13);
    EXPECT_NEAR(passive.evaluate(1.0 + e1).first, 2.0 / e1, 1e-10);
  }
  const auto compressive =
      fm::fiber_compressive_force_length_curve(d.fiber_compressive_force_length);
  EXPECT_NEAR(compressive.value(0.0), 1.0, 1e-14);
  EXPECT_NEAR(compressive.evaluate(0.0).first, -4.0, 1e-10);
  EXPECT_NEAR(compressive.value(0.5), 0.0, 1e-14);
  const auto cos_pennation =
      fm::fiber_compressive_force_cos_pennation_curve(d.fiber_compressive_force_cos_pennation);
  EXPECT_NEAR(cos_pennation.value(0.0), 1.0, 1e-14);
  EXPECT_NEAR(cos_pennation.evaluate(0.0).first, -2.0 / kCos85, 1e-9);
  EXPECT_NEAR(cos_pennation.value(kCos85), 0.0, 1e-14);
}

TEST(Millard2012Curves, DerivativesMatchFiniteDifferences) {
  for (const auto& c : cases()) {
    const auto& curve = c.curve;
    for (const auto& point : interior_points(curve, 15, 0.05)) {
      const double x = point.x, h = default_step(x, point.segment_width);
      const fm::BezierCurveJet jet = curve.evaluate(x);
      EXPECT_MATCHES_FINITE_DIFFERENCE(
          jet.first, central_difference([&](double t) { return curve.value(t); }, x, h))
          << c.name << " x " << x;
      EXPECT_MATCHES_FINITE_DIFFERENCE(
          jet.second, central_difference([&](double t) { return curve.evaluate(t).first; }, x, h))
          << c.name << " x " << x;
      EXPECT_MATCHES_FINITE_DIFFERENCE(
          jet.third, central_difference([&](double t) { return curve.evaluate(t).second; }, x, h))
          << c.name << " x " << x;
    }
  }
}

TEST(Millard2012Curves, JointsAndEndsAreC2) {
  for (const auto& c : cases()) {
    const auto& curve = c.curve;
    double slope_scale = 0.0, curvature_scale = 0.0;
    for (const auto& point : interior_points(curve, 50, 0.0)) {
      const auto jet = curve.evaluate(point.x);
      slope_scale = std::max(slope_scale, std::abs(jet.first));
      curvature_scale = std::max(curvature_scale, std::abs(jet.second));
    }
    std::vector<double> joints = {curve.x_begin()};
    for (const auto& s : curve.segments()) joints.push_back(s.x[5]);
    for (double x : joints) {
      // Left and right limits: the last double below the joint, and the joint itself (which
      // belongs to the segment starting there, or to the straight continuation at x_begin).
      const double below = std::nextafter(x, -std::numeric_limits<double>::infinity());
      const double above =
          x == curve.x_end() ? std::nextafter(x, std::numeric_limits<double>::infinity()) : x;
      const auto left = curve.evaluate(below), right = curve.evaluate(above);
      EXPECT_NEAR(left.value, right.value, 1e-13 * std::max(1.0, largest_abs(c.reference, true)))
          << c.name << " " << x;
      EXPECT_NEAR(left.first, right.first, 1e-11 * slope_scale) << c.name << " " << x;
      // Millard's corners have zero curvature at both ends: d2y/dx2 is 0 at every joint.
      EXPECT_NEAR(left.second, 0.0, 1e-11 * curvature_scale) << c.name << " " << x;
      EXPECT_NEAR(right.second, 0.0, 1e-11 * curvature_scale) << c.name << " " << x;
    }
  }
}

TEST(Millard2012Curves, TendonThirdDerivativeJumpsAtTheToeEnd) {
  // C2, not C3: d3F/dL3 jumps to 0 where the toe meets the straight part.
  const auto tendon = fm::tendon_force_length_curve({});
  const double toe_end = tendon.x_end();
  EXPECT_EQ(tendon.evaluate(std::nextafter(toe_end, 2.0)).third, 0.0);
  EXPECT_GT(std::abs(tendon.evaluate(toe_end).third), 1.0);
}

TEST(Millard2012Curves, TendonLengthFromForceRoundTrips) {
  const auto tendon = fm::tendon_force_length_curve({});
  for (double force = 1e-6; force < 3.0; force *= 1.2) {
    const double length = tendon.inverse(force);
    EXPECT_NEAR(tendon.value(length), force, 1e-12 * std::max(force, 1e-2)) << force;
  }
  for (double strain = 0.002; strain < 0.15; strain += 0.001) {
    const double force = tendon.value(1.0 + strain);
    EXPECT_NEAR(tendon.inverse(force) - 1.0, strain, 1e-11 * strain) << strain;
  }
  EXPECT_THROW(tendon.inverse(0.0), std::domain_error);
  EXPECT_THROW(tendon.inverse(-1.0), std::domain_error);
  EXPECT_THROW(tendon.inverse(std::nan("")), std::domain_error);
  EXPECT_THROW(fm::active_force_length_curve({}).inverse(0.5), std::logic_error);
}

TEST(Millard2012Curves, ForceVelocityInverseCurveIsTheExactInverseForTheSameProperties) {
  const auto properties = fm::force_velocity_inverse_curve_defaults();
  const auto fv = fm::force_velocity_curve(properties);
  const auto fv_inverse = fm::force_velocity_inverse_curve(properties);
  for (double v = -1.3; v <= 1.3; v += 0.01) {
    const auto forward = fv.evaluate(v);
    const auto backward = fv_inverse.evaluate(forward.value);
    EXPECT_NEAR(backward.value, v, 1e-12) << v;
    EXPECT_NEAR(backward.first * forward.first, 1.0, 1e-10) << v;
    EXPECT_NEAR(fv.inverse(forward.value), v, 1e-12) << v;
  }
}

TEST(Millard2012Curves, MuscleForceVelocityInverseIsExactOnlyForTheUndampedModel) {
  const fm::Millard2012CurveParameters d;
  // Damped: fv keeps slopes 0 at vmax, the inverse gets half the near slopes, which moves the
  // knots at +-0.9 (force 0.0125 vs 0.01875 on the concentric side): they agree at -1, 0, +1 only.
  const auto damped =
      fm::millard2012_curves(fm::millard2012_muscle_curve_parameters(d, {0.1, false}));
  const auto damped_round_trip = [&](double v) {
    return damped.force_velocity_inverse.value(damped.force_velocity.value(v));
  };
  for (double v : {-1.0, 0.0, 1.0}) EXPECT_NEAR(damped_round_trip(v), v, 1e-12) << v;
  EXPECT_GT(std::abs(damped_round_trip(-0.9) + 0.9), 1e-2);
  EXPECT_GT(std::abs(damped_round_trip(0.5) - 0.5), 1e-2);
  // Undamped: the muscle raises fv's slopes at vmax to half the near ones, as the inverse has them.
  const auto classic =
      fm::millard2012_curves(fm::millard2012_muscle_curve_parameters(d, {0.0, false}));
  for (double v = -1.3; v <= 1.3; v += 0.01)
    EXPECT_NEAR(classic.force_velocity_inverse.value(classic.force_velocity.value(v)), v, 1e-12)
        << v;
}

TEST(Millard2012Curves, MuscleAdjustsItsCurvesToItsFormulation) {
  fm::Millard2012CurveParameters p;
  p.force_velocity.concentric_slope_at_vmax = 0.05;
  const auto damped = fm::millard2012_muscle_curve_parameters(p, {0.1, false});
  EXPECT_EQ(damped.active_force_length.minimum_value, 0.0);
  EXPECT_EQ(damped.force_velocity.concentric_slope_at_vmax, 0.0);
  const auto rigid = fm::millard2012_muscle_curve_parameters(p, {0.0, true});
  EXPECT_EQ(rigid.active_force_length.minimum_value, 0.0);
  const auto classic =
      fm::millard2012_muscle_curve_parameters(p, {0.0009, false});  // < 0.001: undamped
  EXPECT_EQ(classic.active_force_length.minimum_value, 0.1);
  EXPECT_EQ(classic.force_velocity.concentric_slope_at_vmax, 0.125);
  EXPECT_EQ(classic.force_velocity.eccentric_slope_at_vmax, 0.075);
  p.force_velocity.eccentric_slope_near_vmax = 1e-9;
  EXPECT_THROW(fm::millard2012_muscle_curve_parameters(p, {}), std::invalid_argument);
}

TEST(Millard2012Curves, DefaultsAreOpenSims) {
  const fm::Millard2012CurveParameters d;
  EXPECT_EQ(d.active_force_length.min_norm_active_fiber_length, 0.47 - 0.0259);
  EXPECT_EQ(d.force_velocity.max_eccentric_velocity_force_multiplier, 1.4);
  EXPECT_EQ(d.force_velocity.concentric_curviness, 0.6);
  EXPECT_EQ(d.force_velocity.eccentric_curviness, 0.9);
  const auto passive = fm::resolved(d.fiber_force_length);
  EXPECT_EQ(*passive.stiffness_at_low_force, 0.2);
  EXPECT_DOUBLE_EQ(*passive.stiffness_at_one_norm_force, 2.0 / 0.7);
  EXPECT_EQ(*passive.curviness, 0.75);
  const auto tendon = fm::resolved(d.tendon_force_length);
  EXPECT_DOUBLE_EQ(*tendon.stiffness_at_one_norm_force, 1.375 / 0.049);
  EXPECT_DOUBLE_EQ(*tendon.norm_force_at_toe_end, 2.0 / 3.0);
  EXPECT_EQ(*tendon.curviness, 0.5);
  EXPECT_DOUBLE_EQ(*fm::resolved(d.fiber_compressive_force_length).stiffness_at_zero_length, -4.0);
  EXPECT_DOUBLE_EQ(
      *fm::resolved(d.fiber_compressive_force_cos_pennation).stiffness_at_perpendicular,
      -2.0 / kCos85);
}

TEST(Millard2012Curves, BadPropertiesAreRejectedByName) {
  const auto expect_rejected = [](auto make, const std::string& field) {
    try {
      make();
      ADD_FAILURE() << "no exception for " << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  fm::ActiveForceLengthCurveProperties active;
  active.shallow_ascending_slope = 4.0;
  expect_rejected([&] { fm::active_force_length_curve(active); }, "shallow_ascending_slope");
  active = {};
  active.transition_norm_fiber_length = 1.0;
  expect_rejected([&] { fm::active_force_length_curve(active); }, "transition_norm_fiber_length");
  fm::ForceVelocityCurveProperties velocity;
  velocity.max_eccentric_velocity_force_multiplier = 1.0;
  expect_rejected([&] { fm::force_velocity_curve(velocity); },
                  "max_eccentric_velocity_force_multiplier");
  expect_rejected([&] { fm::force_velocity_inverse_curve({}); }, "concentric_slope_at_vmax");
  velocity = {};
  velocity.eccentric_curviness = 1.5;
  expect_rejected([&] { fm::force_velocity_curve(velocity); }, "eccentric_curviness");
  fm::FiberForceLengthCurveProperties passive;
  passive.curviness = 0.5;  // the other optional properties unset
  expect_rejected([&] { fm::fiber_force_length_curve(passive); }, "all set or all unset");
  fm::TendonForceLengthCurveProperties tendon;
  tendon.stiffness_at_one_norm_force = 30.0;
  tendon.norm_force_at_toe_end = 1.0;
  tendon.curviness = 0.5;
  expect_rejected([&] { fm::tendon_force_length_curve(tendon); }, "norm_force_at_toe_end");
  tendon.norm_force_at_toe_end = 0.5;
  tendon.stiffness_at_one_norm_force = 10.0;  // <= 1 / 0.049
  expect_rejected([&] { fm::tendon_force_length_curve(tendon); }, "stiffness_at_one_norm_force");
  EXPECT_THROW(fm::tendon_force_length_curve({}).value(std::nan("")), std::invalid_argument);
  EXPECT_THROW(fm::quintic_bezier_corner(0, 0, 1, 1, 1, 1.5, 0.5, "test"),
               std::invalid_argument);  // no C corner
}
