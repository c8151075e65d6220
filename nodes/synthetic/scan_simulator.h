#pragma once
// A terrestrial laser scanner ray-cast through an analytic scene: the built-in input of
// `meshflow demo` and ground truth for tests.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "nodes/synthetic/shapes.h"
#include "runtime/point_cloud.h"

namespace meshflow::synthetic {

/// A room (seen from inside) furnished with solid boxes and spheres.
struct Scene {
  Box room;
  std::vector<Box> boxes;
  std::vector<Sphere> spheres;
};

/// An 8 x 6 x 3 m room with a table-sized box, a cabinet and a ball.
Scene demo_room_scene();

struct ScanConfig {
  Eigen::Vector3f origin = {0.0f, 0.0f, 1.2f};  ///< scanner position, metres
  int azimuth_steps = 720;                      ///< rays per full turn
  int elevation_steps = 240;                    ///< rays from min to max elevation
  float min_elevation_deg = -70.0f;
  float max_elevation_deg = 70.0f;
  float noise_sigma = 0.0f;  ///< Gaussian range noise, metres
  std::uint32_t seed = 1;
};

/// One point per ray that hits the scene (all rays do inside a closed room), with the sensor
/// origin set. Parallel over rays; noise is a hash of (seed, ray), so the output is
/// deterministic for any thread count. O(rays x objects).
PointCloud simulate_scan(const Scene& scene, const ScanConfig& config);

/// Distance along the unit direction `d` from `o` to the first surface hit (infinity if none).
float cast_ray(const Scene& scene, const Eigen::Vector3f& o, const Eigen::Vector3f& d);

/// Unsigned distance from p to the nearest surface of the scene, metres.
float surface_distance(const Scene& scene, const Eigen::Vector3f& p);

}  // namespace meshflow::synthetic
