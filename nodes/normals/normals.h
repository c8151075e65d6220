#pragma once
// Normal estimation by k-nearest-neighbour PCA plane fits (Hoppe et al. 1992), oriented towards
// the sensor and smoothed by interpolation over neighbours (Wiemann 2013, LVR).

#include <Eigen/Core>
#include <vector>

#include "nodes/normals/spatial_index.h"
#include "runtime/point_cloud.h"

namespace meshflow {

enum class NormalOrientation {
  kTowardSensor,      ///< towards cloud.sensor_origin (falls back to `viewpoint` without one)
  kTowardViewpoint,   ///< towards NormalsConfig::viewpoint
  kAwayFromViewpoint  ///< away from `viewpoint` (e.g. the centre of a closed object)
};

struct NormalsConfig {
  int kn = 10;  ///< neighbours of the plane fit (thesis default kn = 10)
  int ki = 10;  ///< neighbours averaged in normal interpolation; 0 or 1 = off (thesis ki = 10)
  /// Thesis bounding-box criterion: when the kn neighbours' bounding box (taken in their
  /// principal frame) is degenerate, its middle extent below `adaptive_ratio` x its largest as
  /// for points along one laser line, k is doubled until the box is well shaped or
  /// `adaptive_max_k` is reached.
  bool adaptive_k = false;
  float adaptive_ratio = 0.2f;
  int adaptive_max_k = 80;
  NormalOrientation orientation = NormalOrientation::kTowardSensor;
  Eigen::Vector3f viewpoint = Eigen::Vector3f::Zero();  ///< metres, world frame
};

/// Unit normals for every point of `cloud` (finite positions required). `index` must be built
/// over cloud.positions. Output independent of the thread count. Parallel over points;
/// O(n (kn + ki) log n). Points with fewer than 3 neighbours get the direction to the viewpoint.
std::vector<Eigen::Vector3f> estimate_normals(const PointCloud& cloud, const SpatialIndex& index,
                                              const NormalsConfig& config);

/// Normal of the least-squares plane through `points` (smallest-eigenvalue eigenvector of the
/// covariance), unit length, arbitrary sign; zero vector for fewer than 3 points.
Eigen::Vector3f fit_plane_normal(const std::vector<Eigen::Vector3f>& points);

}  // namespace meshflow
