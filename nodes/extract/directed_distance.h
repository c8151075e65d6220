#pragma once
// Directed distances (Kobbelt et al. 2001, "Feature sensitive surface extraction from volume
// data"): where a grid edge crosses the surface, measured along the edge itself instead of
// interpolated from the corner values. For point data the surface near a point is its oriented
// disk (the point's tangent plane within a radius), as in the reconstruction thesis.

#include <Eigen/Core>

#include "nodes/search/spatial_index.h"
#include "runtime/point_cloud.h"

namespace meshflow {

struct DirectedDistanceConfig {
  int neighbours = 8;               ///< points whose disks are tried per edge
  float disk_radius_voxels = 1.0f;  ///< radius of each point's disk, in voxels
  /// Disks whose normal makes an angle above acos(min_normal_along_edge) with the edge are
  /// grazing and skipped (their intersection is ill-conditioned).
  float min_normal_along_edge = 0.1f;
};

/// Where a crossed edge meets the surface, and the surface normal there.
struct EdgeHit {
  Eigen::Vector3f position;
  Eigen::Vector3f normal;
  bool from_disk = false;  ///< false: no disk fitted; `position` is the caller's guess
};

/// Intersects the edge from `lower` (metres) along the unit axis `axis` (0, 1, 2), `length`
/// metres long, with the disks of the points nearest to `guess` (the interpolated crossing),
/// at signed offset `iso` along each disk's normal. `inside_at_lower` tells which way the edge
/// leaves the solid: only disks whose normal points the same way qualify (so the faces of a
/// sharp edge that the grid edge does not cross are never used). Of the disks hit within the
/// edge, the one hit closest to its centre wins. Without a qualifying disk: `guess` and the
/// nearest point's normal. Needs cloud normals; thread-safe; O(log n + neighbours).
EdgeHit directed_edge_hit(const Eigen::Vector3f& lower, int axis, float length,
                          bool inside_at_lower, const Eigen::Vector3f& guess, float iso,
                          const PointCloud& cloud, const SpatialIndex& index, float voxel_size,
                          const DirectedDistanceConfig& config = {});

}  // namespace meshflow
