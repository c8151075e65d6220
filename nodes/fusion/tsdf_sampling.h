#pragma once
// Reading a TSDF map at arbitrary points (a mesh's vertices): trilinear samples of its voxels.

#include <Eigen/Core>
#include <vector>

#include "nodes/fusion/tsdf_map.h"

namespace meshflow {

/// The accumulated weight of `map` at each of `points` (metres, the map's frame), trilinear
/// over the 8 voxels around the point (voxels of blocks never allocated weigh 0; points outside
/// the map's range or not finite get 0). Under the default constant weighting this is how many
/// frames observed the surface there, capped at config().max_weight. Parallel over points,
/// deterministic; not thread-safe against integrate() on the same map. O(points).
std::vector<float> tsdf_weights_at(const TsdfMap& map, const std::vector<Eigen::Vector3f>& points);

}  // namespace meshflow
