#include "nodes/extract/directed_distance.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace meshflow {

EdgeHit directed_edge_hit(const Eigen::Vector3f& lower, int axis, float length,
                          bool inside_at_lower, const Eigen::Vector3f& guess, float iso,
                          const PointCloud& cloud, const SpatialIndex& index, float voxel_size,
                          const DirectedDistanceConfig& config) {
  constexpr std::size_t kMaxNeighbours = 64;
  std::array<std::uint32_t, kMaxNeighbours> ids;
  std::array<float, kMaxNeighbours> squared;
  const std::size_t k = index.knn(
      guess, std::min<std::size_t>(kMaxNeighbours, static_cast<std::size_t>(config.neighbours)),
      ids.data(), squared.data());
  EdgeHit hit{guess, Eigen::Vector3f::Zero(), false};
  if (k == 0) return hit;
  hit.normal = cloud.normals[ids[0]];
  // Leaving the solid along +axis means the outward normal has a positive axis component.
  const float exit_sign = inside_at_lower ? 1.0f : -1.0f;
  const float radius = config.disk_radius_voxels * voxel_size;
  float best = radius * radius;
  for (std::size_t i = 0; i < k; ++i) {
    const Eigen::Vector3f& p = cloud.positions[ids[i]];
    const Eigen::Vector3f& n = cloud.normals[ids[i]];
    const float along = n[axis] * exit_sign;
    if (!(along >= config.min_normal_along_edge)) continue;  // also rejects NaN normals
    // n . (lower + t e_axis - p) = iso  ->  t = (iso - n . (lower - p)) / n_axis.
    const float t = (iso - n.dot(lower - p)) / n[axis];
    if (!(t >= 0.0f && t <= length)) continue;
    Eigen::Vector3f x = lower;
    // Kept off the corners (as the interpolated vertices are) so no two vertices coincide.
    x[axis] += std::clamp(t, 1e-3f * length, (1.0f - 1e-3f) * length);
    const float r2 = (x - p).squaredNorm();
    if (r2 < best) {
      best = r2;
      hit = EdgeHit{x, n, true};
    }
  }
  return hit;
}

}  // namespace meshflow
