#pragma once
// OpenSim's range checks on the Millard (2013) curve properties (SmoothSegmentedFunctionFactory
// and the curve classes), as std::invalid_argument naming the curve and the property. The
// optional properties are checked after resolution, so they are set.

#include "flatsos/muscles/millard2012_curves.hpp"

namespace flatsos::muscles::detail {

inline constexpr double kPi = 3.14159265358979323846;

void check(const ActiveForceLengthCurveProperties& properties);
void check_force_velocity(const ForceVelocityCurveProperties& properties);
void check_force_velocity_inverse(const ForceVelocityCurveProperties& properties);
void check(const FiberForceLengthCurveProperties& resolved_properties);
void check(const TendonForceLengthCurveProperties& resolved_properties);
void check(const FiberCompressiveForceLengthCurveProperties& resolved_properties);
void check(const FiberCompressiveForceCosPennationCurveProperties& resolved_properties);

}  // namespace flatsos::muscles::detail
