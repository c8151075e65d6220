#pragma once
// Analytic shapes for ground truth: exact surface distances and dense surface samples.

#include <Eigen/Core>
#include <cstdint>

#include "runtime/point_cloud.h"

namespace meshflow::synthetic {

struct Sphere {
  Eigen::Vector3f center = Eigen::Vector3f::Zero();
  float radius = 1.0f;
};

/// Solid axis-aligned box.
struct Box {
  Eigen::Vector3f center = Eigen::Vector3f::Zero();
  Eigen::Vector3f half_size = Eigen::Vector3f::Ones();
};

/// Two half-planes joined by a vertical step: z = 0 for x < 0, z = height for x >= 0, and the
/// wall x = 0, 0 <= z <= height. Samples cover |x|, |y| <= half_extent.
struct StepPlane {
  float half_extent = 1.0f;
  float height = 0.2f;
};

/// Signed distance to the box surface (negative inside), metres.
float signed_distance(const Box& box, const Eigen::Vector3f& p);

/// Unsigned distance from p to the surface, metres.
float surface_distance(const Sphere& s, const Eigen::Vector3f& p);
float surface_distance(const Box& b, const Eigen::Vector3f& p);
float surface_distance(const StepPlane& s, const Eigen::Vector3f& p);

/// Points on the surface about `spacing` metres apart, each moved by isotropic Gaussian noise
/// of standard deviation `noise_sigma` metres. Deterministic for a given seed. No normals.
PointCloud sample_surface(const Sphere& s, float spacing, float noise_sigma, std::uint32_t seed);
PointCloud sample_surface(const Box& b, float spacing, float noise_sigma, std::uint32_t seed);
PointCloud sample_surface(const StepPlane& s, float spacing, float noise_sigma, std::uint32_t seed);

}  // namespace meshflow::synthetic
