#pragma once
// Degrees to radians, for the configuration angles (given in degrees) of the kernels.

namespace meshflow {

/// Radians per degree (pi / 180).
constexpr double kRadiansPerDegree = 3.14159265358979323846 / 180.0;

/// `degrees` in radians. O(1).
constexpr double radians(double degrees) { return degrees * kRadiansPerDegree; }
constexpr float radians(float degrees) { return degrees * static_cast<float>(kRadiansPerDegree); }

}  // namespace meshflow
