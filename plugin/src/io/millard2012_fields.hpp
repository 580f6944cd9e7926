#pragma once
// Every curve property of a Millard2012EquilibriumMuscle (millard2012_curves.hpp) by the names
// files use: OpenSim's curve element (<ActiveForceLengthCurve>) and property tag, and the model
// file's curve key ("active_force_length") with the same property name. One list, read by the
// .osim mapping (opensim_muscle_models.cpp) and the model file's reader and writer
// (model_file_millard.cpp), so that the three cannot drift apart.

#include <optional>
#include <string_view>

#include "flatsos/muscles/millard2012_curves.hpp"

namespace flatsos::plugin::millard2012_fields {

/// Calls visit(osim_curve, json_curve, property, field) for every property, where field is a
/// double& (a property OpenSim always has) or a std::optional<double>& (an optional one: unset
/// means OpenSim's computed default). Parameters may be const.
template <class Parameters, class Visitor>
void for_each_property(Parameters& c, Visitor&& visit) {
  auto& afl = c.active_force_length;
  const char* curve = "ActiveForceLengthCurve";
  const char* key = "active_force_length";
  visit(curve, key, "min_norm_active_fiber_length", afl.min_norm_active_fiber_length);
  visit(curve, key, "transition_norm_fiber_length", afl.transition_norm_fiber_length);
  visit(curve, key, "max_norm_active_fiber_length", afl.max_norm_active_fiber_length);
  visit(curve, key, "shallow_ascending_slope", afl.shallow_ascending_slope);
  visit(curve, key, "minimum_value", afl.minimum_value);
  auto& fv = c.force_velocity;
  curve = "ForceVelocityCurve", key = "force_velocity";
  visit(curve, key, "concentric_slope_at_vmax", fv.concentric_slope_at_vmax);
  visit(curve, key, "concentric_slope_near_vmax", fv.concentric_slope_near_vmax);
  visit(curve, key, "isometric_slope", fv.isometric_slope);
  visit(curve, key, "eccentric_slope_at_vmax", fv.eccentric_slope_at_vmax);
  visit(curve, key, "eccentric_slope_near_vmax", fv.eccentric_slope_near_vmax);
  visit(curve, key, "max_eccentric_velocity_force_multiplier", fv.max_eccentric_velocity_force_multiplier);
  visit(curve, key, "concentric_curviness", fv.concentric_curviness);
  visit(curve, key, "eccentric_curviness", fv.eccentric_curviness);
  auto& fpe = c.fiber_force_length;
  curve = "FiberForceLengthCurve", key = "fiber_force_length";
  visit(curve, key, "strain_at_zero_force", fpe.strain_at_zero_force);
  visit(curve, key, "strain_at_one_norm_force", fpe.strain_at_one_norm_force);
  visit(curve, key, "stiffness_at_low_force", fpe.stiffness_at_low_force);
  visit(curve, key, "stiffness_at_one_norm_force", fpe.stiffness_at_one_norm_force);
  visit(curve, key, "curviness", fpe.curviness);
  auto& fse = c.tendon_force_length;
  curve = "TendonForceLengthCurve", key = "tendon_force_length";
  visit(curve, key, "strain_at_one_norm_force", fse.strain_at_one_norm_force);
  visit(curve, key, "stiffness_at_one_norm_force", fse.stiffness_at_one_norm_force);
  visit(curve, key, "norm_force_at_toe_end", fse.norm_force_at_toe_end);
  visit(curve, key, "curviness", fse.curviness);
  auto& fcl = c.fiber_compressive_force_length;
  curve = "FiberCompressiveForceLengthCurve", key = "fiber_compressive_force_length";
  visit(curve, key, "norm_length_at_zero_force", fcl.norm_length_at_zero_force);
  visit(curve, key, "stiffness_at_zero_length", fcl.stiffness_at_zero_length);
  visit(curve, key, "curviness", fcl.curviness);
  auto& fcp = c.fiber_compressive_force_cos_pennation;
  curve = "FiberCompressiveForceCosPennationCurve", key = "fiber_compressive_force_cos_pennation";
  visit(curve, key, "engagement_angle_in_degrees", fcp.engagement_angle_in_degrees);
  visit(curve, key, "stiffness_at_perpendicular", fcp.stiffness_at_perpendicular);
  visit(curve, key, "curviness", fcp.curviness);
}

/// The curves an OpenSim Millard2012EquilibriumMuscle has as properties (the compressive ones
/// belong to Millard2012AccelerationMuscle).
inline bool equilibrium_muscle_curve(const char* osim_curve) {
  const std::string_view c = osim_curve;
  return c != "FiberCompressiveForceLengthCurve" && c != "FiberCompressiveForceCosPennationCurve";
}

}  // namespace flatsos::plugin::millard2012_fields
