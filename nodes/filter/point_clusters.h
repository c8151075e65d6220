#pragma once
// Outliers that cannot make surfaces: points whose cluster — the points linked to them through
// nearest-neighbour links no longer than a radius — is too small to carry a surface (isolated
// points and sparse clusters, e.g. a scanner's mixed pixels or stray returns scattered in a
// scan's bounding box). Works on the kd-tree the pipeline already built for normals.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "nodes/search/spatial_index.h"
#include "runtime/point_cloud.h"

namespace meshflow {

/// What surface_cluster_indices() dropped.
struct ClusterCounts {
  std::size_t isolated = 0;  ///< points without any neighbour within the link radius
  std::size_t sparse = 0;    ///< points in clusters of 2 .. min_points - 1 points
  std::size_t clusters = 0;  ///< clusters of at least min_points points (kept)
};

struct ClusterConfig {
  /// Clusters with fewer points are dropped; 0 or 1 = keep every point.
  std::size_t min_points = 20;
  /// Longest link between two points of one cluster, metres (> 0).
  float link_radius = 0.0f;
  /// Nearest neighbours each point links to first (when within link_radius) where the grid
  /// cannot be used (a cloud wider than 2^21 cells): enough to join a densely sampled surface,
  /// a thin wall or a pole without a radius query per point.
  int k = 8;
};

/// Indices (ascending) of the points in clusters of at least config.min_points points, where a
/// cluster is a connected component of the graph linking every two points at most
/// config.link_radius apart (the kd-tree's squared distance, inclusive). Found on a grid of
/// cells a little under link_radius / sqrt(3) (a cell's points are linked; two cells within 2
/// along each axis are linked when some pair of their points is); `index` (built over
/// cloud.positions) only for a cloud wider than 2^21 cells, linked through each point's
/// config.k nearest neighbours within the radius, then the points of clusters still too small
/// to all their neighbours within it (the same clusters). A thin structure sampled at the
/// surface's spacing stays one cluster; a point farther than link_radius from every other is
/// isolated. Parallel on the grid (a radix sort of the points by cell, a concurrent union-find
/// of the cells), deterministic: the result does not depend on the thread count. O(n log n) at most
/// for the sort, plus the point pairs of unlinked neighbouring cells; O(n) memory. Thread-safe
/// (reads only).
std::vector<std::uint32_t> surface_cluster_indices(const PointCloud& cloud,
                                                   const SpatialIndex& index,
                                                   const ClusterConfig& config,
                                                   ClusterCounts* counts = nullptr);

}  // namespace meshflow
