#pragma once
// Signed distance at the corners of a sparse grid: Hoppe et al. (1992) tangent-plane distance,
// averaged over the kd nearest points as in the thesis (Wiemann 2013, kd = 5).

#include <cstdint>
#include <vector>

#include "nodes/normals/spatial_index.h"
#include "nodes/voxelize/sparse_grid.h"
#include "runtime/point_cloud.h"

namespace meshflow {

struct DistanceConfig {
  int kd = 5;  ///< tangent planes averaged per corner (thesis default kd = 5)
  /// A corner farther than this many voxels from its nearest point is invalid: no surface is
  /// extracted in cells that touch it, so nothing is invented away from the data.
  float max_distance_voxels = 2.0f;
};

/// Signed distances (metres) per grid corner: positive on the side the normals point to.
struct DistanceField {
  std::vector<float> values;        ///< one per grid corner
  std::vector<std::uint8_t> valid;  ///< 1 where values[i] is meaningful
  std::size_t valid_count() const;
};

/// d(q) = mean over the kd nearest points p_i of n_i . (q - p_i). Requires an index over
/// cloud.positions and one normal per point (else throws meshflow::Error). Parallel over corners,
/// deterministic; O(corners kd log n).
DistanceField hoppe_distance(const SparseGrid& grid, const PointCloud& cloud,
                             const SpatialIndex& index, const DistanceConfig& config);

}  // namespace meshflow
