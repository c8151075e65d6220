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
  /// Every cell that overlaps the cube of half-size `margin` voxels around a point is created,
  /// not only the cell containing it, so a surface passing near a cell border is never cut off
  /// at a missing neighbour cell. 0.5 = the 2 x 2 x 2 cells nearest to each point.
  float margin = 0.5f;
};

/// Cells are addressed by the packed index of their minimum corner; corner c of a cell
/// (c = x + 2y + 4z, bits selecting +1 along each axis) is cell_corners[cell][c].
struct SparseGrid {
  float voxel_size = 0.0f;
  std::vector<VoxelKey> cells;                             ///< sorted, unique
  std::vector<VoxelKey> corners;                           ///< sorted, unique
  std::vector<std::array<std::uint32_t, 8>> cell_corners;  ///< indices into `corners`

  /// World position (metres) of corner i.
  Eigen::Vector3f corner_position(std::size_t i) const {
    return unpack_key(corners[i]).cast<float>() * voxel_size;
  }
  /// Index of the corner with integer index c, or UINT32_MAX if the grid lacks it. O(log n).
  std::uint32_t find_corner(const Eigen::Vector3i& c) const;
};

/// Builds the grid from sorted unique keys (deterministic, no locks): the cells around every
/// point (radix sort + unique), then their corners by separable merges, then each cell's corner
/// indices by linear walks. Throws meshflow::Error if a point lies outside the packable range
/// (about +-1e6 cells) or the voxel size or margin is invalid. O(n + cells), parallel inside.
SparseGrid voxelize(const PointCloud& cloud, const VoxelizeConfig& config);

/// A voxel size suited to the sampling: `factor` x the median nearest-neighbour spacing of a
/// deterministic subset of the points, and at least 1/2000 of the bounding-box diagonal
/// (which bounds memory). `index` must be built over cloud.positions. Returns metres; 0 when
/// all points coincide.
class SpatialIndex;
float suggest_voxel_size(const PointCloud& cloud, const SpatialIndex& index, float factor = 3.0f);

/// For a cloud back-projected from a depth image with focal length `focal_px`: `factor` x the
/// pixel footprint (distance / focal) at the median distance from the sensor. Metres.
float suggest_voxel_size_for_depth(const PointCloud& cloud, float focal_px, float factor = 3.0f);

}  // namespace meshflow
