#pragma once
// The voxelize stage: the sparse voxel grid around a point cloud, with corner samples shared
// between neighbouring cells (thesis: shared query points), so each corner's distance is
// computed once; and the voxel size a cloud's sampling suggests.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "runtime/point_cloud.h"
#include "runtime/sparse_grid.h"

namespace meshflow {

struct VoxelizeConfig {
  float voxel_size = 0.05f;  ///< cell edge in metres
  /// Every cell that overlaps the cube of half-size `margin` voxels around a point is created,
  /// not only the cell containing it, so a surface passing near a cell border is never cut off
  /// at a missing neighbour cell. 0.5 = the 2 x 2 x 2 cells nearest to each point.
  float margin = 0.5f;
};

/// Builds the grid from sorted unique keys (deterministic, no locks): the cells around every
/// point (radix sort + unique), then their corners by separable merges, then each cell's corner
/// indices by linear walks. Throws meshflow::Error if a point lies outside the packable range
/// (about +-1e6 cells) or the voxel size or margin is invalid. O(n + cells), parallel inside.
SparseGrid voxelize(const PointCloud& cloud, const VoxelizeConfig& config);

/// Removes every cell of `grid` outside `range` and the corners only they used (the chunked
/// path keeps the cells a chunk owns, so each cell's surface comes from exactly one chunk).
/// Keys stay sorted; corner indices are renumbered. Serial; O(cells + corners).
void keep_cells_in(SparseGrid& grid, const CellRange& range);

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
