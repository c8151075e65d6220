#pragma once
// Per-vertex quality of a reconstruction: how far each mesh vertex lies from the data it was
// made from. Written as the optional PLY vertex property `quality` (reconstruct/run --quality).

#include <Eigen/Core>
#include <vector>

namespace meshflow {

/// For each of `queries`, the Euclidean distance (metres) to the nearest of `points` (kd-tree,
/// exact). Non-finite points are skipped; with no finite point every distance is +infinity.
/// Parallel over queries, deterministic (each result depends on its query only).
/// O((Q + P) log P).
std::vector<float> nearest_point_distances(const std::vector<Eigen::Vector3f>& queries,
                                           const std::vector<Eigen::Vector3f>& points);

/// What supports each vertex of a mesh made from one cloud.
struct VertexSupport {
  std::vector<float> distances;     ///< metres to the nearest point (nearest_point_distances())
  std::vector<float> observations;  ///< points within the radius (a count, as a float)
};

/// Statistics of per-vertex observation counts, the low end first (where data is thin).
struct ObservationStats {
  double mean = 0.0;
  float min = 0.0f, p5 = 0.0f, median = 0.0f;  ///< nearest rank; 0 for no values
  std::size_t vertices = 0;
};

/// ObservationStats of `counts`. O(n) (two selections).
ObservationStats observation_stats(std::vector<float> counts);

/// For each of `queries`: the distance to the nearest finite point of `points` and how many
/// finite points lie within `radius` metres (> 0; e.g. the reconstruction's voxel size): the
/// measurements that support the vertex. One kd-tree for both. Parallel over queries,
/// deterministic. Throws meshflow::Error for a radius that is not positive and finite.
/// O((Q + P) log P + Q k), k the points found per query.
VertexSupport vertex_support(const std::vector<Eigen::Vector3f>& queries,
                             const std::vector<Eigen::Vector3f>& points, float radius);

}  // namespace meshflow
