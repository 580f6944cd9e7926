#pragma once
// Bounded receding-horizon steps: what a step's plan asks of the muscles over its first control
// period kept inside 0 <= n <= 1 and floor <= a <= 1 at the samples the controller applies, by
// construction instead of by the muscle clamping it. With constant flat outputs the tendon forces
// F = C_tau (tau - offset) + C_Y alpha are affine in alpha and their rates do not depend on it,
// so the bounds are smooth rows in the p entries of alpha: the open-loop planner's bound rows and
// sequential LP (bounds/bound_rows.hpp, bounds/sequential_lp.hpp) with the SLP's C_Y alpha >= B, alpha >= 0
// as the linear part, started from the SLP's optimum.

#include <vector>

#include "bounds/bound_rows.hpp"
#include "flatsos/planner/receding_horizon_step.hpp"

namespace flatsos::planner::detail {

/// How far inside its bounds every sample's a and n are put: the controller hands each muscle a
/// polynomial fitted to the samples, which reproduces them to about 1e-6; the margin keeps the
/// samples themselves strictly inside. Reserve rows C_Y alpha >= B hold to half of the other.
constexpr double kSampleMargin = 1e-5;

/// The first period's excitations and activations of the step's current alpha into its buffers
/// (buffers.excitations, buffers.activations, and the period's torque grid); false where they
/// are not finite.
bool sample_period(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const PeriodExcitationBounds& bounds,
                   RecedingHorizonStep& step);

/// The torque jets the muscles supply along the step's path at times i h_s (i < count): the
/// model's inverse dynamics less the step's torque offset.
void muscle_torques(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const RecedingHorizonOptions& options,
                    const RecedingHorizonStep& step, double h_s, int count, TorqueJetGrid& grid);

/// The largest excess of a sample's a or n over its bounds (0 inside), and where.
struct SampleExcess {
  double value = 0.0;
  int sample = 0, muscle = 0;
};
SampleExcess worst_excess(const FlatOutputMap& flat, const RecedingHorizonStep& step);

/// The tendon-force jets of the step's plan at times i h_s (i < count) as affine in alpha (bound
/// points: base + slope alpha, k = 0, 1, 2), from the torque jets of `grid` there (the torque
/// offset already taken off), mixed by the coupling's rates where the moment arms depend on
/// posture (ForceJetMap), with the blend of a step that has a flat-output start.
std::vector<BoundPoint> step_points(const FlatOutputMap& flat, const RecedingHorizonStep& step, const TorqueJetGrid& grid,
                                    double h_s, int count);
/// The same at the first period's samples (after sample_period).
std::vector<BoundPoint> period_points(const FlatOutputMap& flat, const PeriodExcitationBounds& bounds,
                                      const RecedingHorizonStep& step);

/// The first period's excitations and activations for step.alpha() from its bound points
/// (period_points: the samples' own torque jets and force-jet maps, so the same values as
/// sample_period without sampling the plan again) into the step's buffers; sets and returns
/// first_period_sampled: true when every sample is finite and inside its bounds.
bool sampled_at_points(const FlatOutputMap& flat, const std::vector<BoundPoint>& points, RecedingHorizonStep& step);

/// Checks step.alpha() on the first period's samples (step.buffers.excitations / activations
/// hold them afterwards when they are finite) and, when a bound is violated, moves alpha inside:
/// step.slp.alpha, cost, status and message, bounds_imposed and bound_iterations updated.
/// Allocates nothing when the SLP's optimum already meets the bounds and the moment arms are
/// constant. `max_iterations`: the sequential LP's steps.
void impose_period_bounds(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const RecedingHorizonOptions& options,
                          int max_iterations, RecedingHorizonStep& step);

}  // namespace flatsos::planner::detail
