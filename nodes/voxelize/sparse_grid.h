#pragma once
// Sparse voxel grid around a point cloud, with corner samples shared between neighbouring cells
// (thesis: shared query points), so each corner's distance is computed once.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "runtime/point_cloud.h"
#include "runtime/voxel_key.h"

namespace meshflow {

struct VoxelizeConfig {
  float voxel_size = 0.05f;  ///< cell edge in metres
  int dilation = 1;  ///< also create cells within this many cells of an occupied one, so the
                     ///< surface between samples is never cut off at a missing cell
};

/// Cells are addressed by the packed index of their minimum corner; corner c of a cell
/// (c = x + 2y + 4z, bits selecting +1 along each axis) is cell_corners[cell][c].
struct SparseGrid {
  float voxel_size = 0.0f;
  std::vector<VoxelKey> cells;    ///< sorted, unique
  std::vector<VoxelKey> corners;  ///< sorted, unique
  std::vector<std::array<std::uint32_t, 8>> cell_corners;  ///< indices into `corners`

  /// World position (metres) of corner i.
  Eigen::Vector3f corner_position(std::size_t i) const {
    return unpack_key(corners[i]).cast<float>() * voxel_size;
  }
  /// Index of the corner with integer index c, or UINT32_MAX if the grid lacks it. O(log n).
  std::uint32_t find_corner(const Eigen::Vector3i& c) const;
};

/// Builds the grid by parallel sort + unique of cell keys (deterministic, no locks):
/// occupied cells, dilated by config.dilation, then their 8 corners.
/// Throws meshflow::Error if a point lies outside the packable range (about +-1e6 cells) or the
/// voxel size is not positive. O(n log n + cells log cells).
SparseGrid voxelize(const PointCloud& cloud, const VoxelizeConfig& config);

/// A voxel size suited to the sampling: `factor` x the median nearest-neighbour spacing of a
/// deterministic subset of the points, and at least 1/2000 of the bounding-box diagonal
/// (which bounds memory). `index` must be built over cloud.positions. Returns metres.
class SpatialIndex;
float suggest_voxel_size(const PointCloud& cloud, const SpatialIndex& index, float factor = 3.0f);

}  // namespace meshflow
