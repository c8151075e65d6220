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

}  // namespace meshflow
